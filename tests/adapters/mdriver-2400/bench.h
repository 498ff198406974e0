// One compressor driver and its simulator on the real bus engine, simulated time and a simulated
// line (tests/support/bus_rig.h), both made by this adapter's own factories from options as text,
// and the frames of the document the tests expect on the wire.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "codec.h"

namespace drivegate::mdriver {

using namespace std::chrono_literals;
using modbus::Exception;

// Section 3 No.1: the fixed-code check.
inline const Bytes kCheck{0x00, 0x01, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x38};
// Conversion table <通常運転モード>, rows 01 (stop), 00 (reset & stop), 40 (1149 rpm),
// 1C (504 rpm); <連続運転モード> row 40.
inline const Bytes kRunStop{0x00, 0x01, 0x10, 0x02, 0x01, 0x01, 0x00, 0x40};
inline const Bytes kRunReset{0x00, 0x01, 0x10, 0x02, 0x00, 0x01, 0x00, 0x41};
inline const Bytes kRun1149{0x00, 0x01, 0x10, 0x02, 0x40, 0x01, 0x00, 0x01};
inline const Bytes kRun504{0x00, 0x01, 0x10, 0x02, 0x1C, 0x01, 0x00, 0x25};
inline const Bytes kRun1149Continuous{0x00, 0x01, 0x10, 0x02, 0x40, 0xFF, 0x00, 0x03};

// The common block (docs/register-map.md): holding registers command and setpoint_rpm, the
// values of command, and the bits of status.
inline constexpr std::uint16_t kCommandRegister = 0;
inline constexpr std::uint16_t kSetpointRegister = 1;
inline constexpr std::uint16_t kStop = 0, kRunForward = 1, kRunReverse = 2, kQuickStop = 3,
                               kResetFault = 4;
inline constexpr std::uint16_t kOnline = 1u << 0, kRunning = 1u << 1, kFaulted = 1u << 2,
                               kCommLost = 1u << 4, kCommandPending = 1u << 6;

// A run reply as the drive sent it, with R4 (target) and R7 (error) replaced: a drive that does
// not take what it was sent. Other bytes pass unchanged.
inline Bytes with_reply(Bytes reply, std::uint8_t target, std::uint8_t error) {
  // Section 3 No.2: R0 src, R1 dst, R2 command 10, R3 07, R4 target .. R7 error .. R12 checksum.
  if (reply.size() != 13 || reply[2] != 0x10) return reply;
  reply[4] = target;
  reply[7] = error;
  reply[12] = checksum(ByteView(reply).first(12));
  return reply;
}

struct Bench {
  explicit Bench(const test::OptionText& options = {}, Millis poll = 500ms,
                 std::uint32_t address = 1)
      : rig(drivegate_adapter) {
    DeviceConfig c = rig.device_config("compressor", address, options);
    c.poll_interval = poll;
    drive = &rig.add_device(c);
    sim = &rig.add_simulator(address, options);
    rig.start();
  }

  // Online, and the first run reply (the status) is in: the line is idle.
  [[nodiscard]] bool ready() {
    if (!rig.run_until([&] { return drive->online(); }, 3s)) return false;
    rig.run_for(200ms);
    return true;
  }
  // "Run at 1149 rpm" in one request, as a PLC writes it, confirmed, then a second of ramp.
  [[nodiscard]] bool running_at_1149() {
    if (!ready()) return false;
    if (write({kRunForward, 1149}) != Exception::none) return false;
    rig.run_for(1s);
    return true;
  }

  // A write to the common holding registers from `address` on, waited for.
  std::optional<Exception> write(std::vector<std::uint16_t> values,
                                 std::uint16_t address = kCommandRegister) {
    return rig.write_and_wait(*drive, Table::holding, address, std::move(values));
  }
  std::shared_ptr<test::WriteOutcome> start_write(std::vector<std::uint16_t> values,
                                                  std::uint16_t address = kCommandRegister) {
    return rig.write(*drive, Table::holding, address, std::move(values));
  }

  // A point's value as a PLC reads it (u16 points, and u32 ones high word first).
  std::uint32_t read(std::string_view point) {
    const auto regs = rig.read(*drive, point);
    if (regs.size() == 2) return (std::uint32_t{regs[0]} << 16) | regs[1];
    return regs.empty() ? 0xFFFFFFFFu : regs[0];
  }
  std::int32_t read_i16(std::string_view point) {
    return static_cast<std::int16_t>(static_cast<std::uint16_t>(read(point)));
  }

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
  [[nodiscard]] const Bytes& last() const { return rig.sent().back().bytes; }
  std::string control(std::string_view line) { return sim->control(line, rig.now()); }

  test::BusRig rig;
  Device* drive = nullptr;
  Simulator* sim = nullptr;
};

}  // namespace drivegate::mdriver
