// One ED3100 and its simulator on the real bus engine, simulated time and a simulated line
// (tests/support/bus_rig.h), both made by this adapter's own factories from options as text; the
// frames of the document the tests expect on the wire; the common block's addresses and values.
#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "codec.h"

namespace drivegate::ed3100 {

using namespace std::chrono_literals;
using modbus::Exception;

// Document frames at address 0x1F (codec_test.cpp cites their sections).
inline const Bytes kReadParam{0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5};
inline const Bytes kWriteParam{0x1F, 0x06, 0x00, 0x06, 0x13, 0x88, 0x67, 0x23};
inline const Bytes kReadMonitor{0x1F, 0x03, 0x0D, 0x00, 0x00, 0x00, 0x44, 0xD8};
inline const Bytes kReadFault{0x1F, 0x03, 0x0E, 0x01, 0x00, 0x00, 0x15, 0x5C};
inline const Bytes kForward{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04,
                            0x00, 0x1E, 0x10, 0x88, 0x67, 0xE6};
inline const Bytes kReverse{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04,
                            0x00, 0x2E, 0x10, 0x88, 0x67, 0xE9};
inline const Bytes kRunReply{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x49, 0xB6};
inline const Bytes kStop{0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74};

// The common block (docs/register-map.md): holding registers command and setpoint_rpm, the
// values of command, and the bits of status.
inline constexpr std::uint16_t kCommandRegister = 0;
inline constexpr std::uint16_t kSetpointRegister = 1;
inline constexpr std::uint16_t kStopCommand = 0, kRunForward = 1, kRunReverse = 2, kQuickStop = 3,
                               kResetFault = 4;
inline constexpr std::uint16_t kOnline = 1u << 0, kRunning = 1u << 1, kFaulted = 1u << 2,
                               kCommLost = 1u << 4, kCommandPending = 1u << 6;
inline constexpr std::uint16_t kFaultOther = 17;  // Fault::other
// This adapter's holding points with parameters = "00-06": frequency_setpoint, param_00_06.
inline constexpr std::uint16_t kFrequencyRegister = 16;
inline constexpr std::uint16_t kParam0006Register = 17;
// Its fault_code point, which shares its name with the common block's (input 1).
inline constexpr std::uint16_t kFaultCodePoint = 32;

// 9600 8E1, the descriptor's line: 11 bits a character.
inline constexpr std::chrono::nanoseconds kCharacter{11 * 1'000'000'000LL / 9600};
inline std::chrono::nanoseconds on_wire(std::size_t bytes) {
  return kCharacter * static_cast<long>(bytes);
}

inline const test::OptionText kWithParameter{{"parameters", "00-06"}};

struct Bench {
  // The drive at the document's address 0x1F with parameter 00-06 exposed, unless told otherwise;
  // the simulator gets the same options (it reads sim_reply_form).
  explicit Bench(const test::OptionText& options = kWithParameter, std::uint32_t address = 0x1F)
      : rig(drivegate_adapter) {
    drive = &rig.add_device("drive", address, options);
    sim = &rig.add_simulator(address, options);
    rig.start();
  }

  // Online, and the first poll cycle (the monitors after the fault word) is in: the line is idle.
  [[nodiscard]] bool ready() {
    if (!rig.run_until([&] { return drive->online(); }, 3s)) return false;
    rig.run_for(200ms);
    return true;
  }
  // "Run forward at `rpm`" in one request, as a PLC writes it, and the ramp to that speed.
  [[nodiscard]] bool running_at(std::int32_t rpm) {
    if (!ready()) return false;
    if (write({kRunForward, static_cast<std::uint16_t>(rpm)}) != Exception::none) return false;
    return rig.run_until([&] { return speed() == rpm; }, 3s);
  }

  // A write to the holding registers from `address` on, waited for.
  std::optional<Exception> write(std::vector<std::uint16_t> values,
                                 std::uint16_t address = kCommandRegister) {
    return rig.write_and_wait(*drive, Table::holding, address, std::move(values));
  }
  std::shared_ptr<test::WriteOutcome> start_write(std::vector<std::uint16_t> values,
                                                  std::uint16_t address = kCommandRegister) {
    return rig.write(*drive, Table::holding, address, std::move(values));
  }

  // A point's registers as a PLC reads them: u16 points, u32 ones high word first.
  std::uint32_t read(std::string_view point) {
    const auto regs = rig.read(*drive, point);
    if (regs.size() == 2) return (std::uint32_t{regs[0]} << 16) | regs[1];
    return regs.empty() ? 0xFFFFFFFFu : regs[0];
  }
  float read_f32(std::string_view point) { return std::bit_cast<float>(read(point)); }
  std::uint16_t input(std::uint16_t address) {
    const auto regs = rig.read(*drive, Table::input, address, 1);
    return regs.empty() ? 0xFFFF : regs[0];
  }
  std::int32_t speed() { return static_cast<std::int16_t>(read("speed_rpm")); }
  std::int32_t setpoint() { return static_cast<std::int16_t>(read("setpoint_rpm")); }
  std::uint16_t command() { return static_cast<std::uint16_t>(read("command")); }
  std::uint16_t status() { return static_cast<std::uint16_t>(read("status")); }

  // Frames on the wire, resends included, from `from` on.
  [[nodiscard]] std::vector<Bytes> frames(TimePoint from = {}) const {
    std::vector<Bytes> out;
    for (const auto& f : rig.sent()) {
      if (f.at >= from) out.push_back(f.bytes);
    }
    return out;
  }
  [[nodiscard]] std::vector<TimePoint> times_of(const Bytes& frame, TimePoint from = {}) const {
    std::vector<TimePoint> out;
    for (const auto& f : rig.sent()) {
      if (f.at >= from && f.bytes == frame) out.push_back(f.at);
    }
    return out;
  }
  [[nodiscard]] std::size_t count(const Bytes& frame, TimePoint from = {}) const {
    return times_of(frame, from).size();
  }
  // Writes (06 and 10) on the wire from `from` on: polls are 03.
  [[nodiscard]] std::vector<Bytes> writes(TimePoint from = {}) const {
    std::vector<Bytes> out;
    for (const Bytes& f : frames(from)) {
      if (f.size() > 1 && f[1] != kFnRead) out.push_back(f);
    }
    return out;
  }
  std::string control(std::string_view line) { return sim->control(line, rig.now()); }
  std::string sim_state() { return control("state"); }

  test::BusRig rig;
  Device* drive = nullptr;
  Simulator* sim = nullptr;
};

}  // namespace drivegate::ed3100
