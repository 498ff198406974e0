// One washer inverter and its simulator on the real bus engine, simulated time and a simulated
// one-wire line at 4800 8O1 (tests/support/bus_rig.h), both made by this adapter's own factories
// from options as text, and the frames of the document the tests expect on the wire.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "codec.h"

namespace drivegate::nidec {

using namespace std::chrono_literals;
using modbus::Exception;

// Master frames (4.1), each laid out per the section cited.
inline const Bytes kPing7{0xA5, 0x02, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0};  // 5.1
inline const Bytes kPoll{0xA5, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0};   // 5.2
inline const Bytes kCw800{0xA5, 0x09, 0x03, 0x20, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x91};  // 5.3
inline const Bytes kCw1000{0xA5, 0x09, 0x03, 0xE8, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x59};
inline const Bytes kCcw800{0xA5, 0x0B, 0x03, 0x20, 0x00, 0x1E,
                           0x00, 0x00, 0x00, 0x00, 0x93};                                     // 5.4
inline const Bytes kStop{0xA5, 0x27, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x82};   // 5.7
inline const Bytes kBrake{0xA5, 0x29, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8C};  // 5.8
inline const Bytes kFct{0xA5, 0x66, 0x12, 0x00, 0x34, 0x00, 0x56, 0x00, 0x78, 0x00, 0xCB};  // 5.15

// The common block (docs/register-map.md): holding registers command and setpoint_rpm, the
// values of command, and the bits of status.
inline constexpr std::uint16_t kCommandRegister = 0;
inline constexpr std::uint16_t kSetpointRegister = 1;
namespace cmd {
inline constexpr std::uint16_t stop = 0, run_forward = 1, run_reverse = 2, quick_stop = 3,
                               reset_fault = 4;
}  // namespace cmd
inline constexpr std::uint16_t kOnline = 1u << 0, kRunning = 1u << 1, kFaulted = 1u << 2,
                               kCommLost = 1u << 4, kCommandPending = 1u << 6;

// A frame's time on this line: section 3, 4800 baud, 8 data bits, odd parity, one stop bit.
inline std::chrono::nanoseconds on_wire(std::size_t bytes) {
  return character_time(kLine.baud, kLine.parity, kLine.data_bits, kLine.stop_bits) *
         static_cast<long>(bytes);
}

struct Bench {
  explicit Bench(const test::OptionText& options = {}, Millis poll = 500ms)
      : rig(drivegate_adapter) {
    DeviceConfig c = rig.device_config("washer", 0, options);
    c.poll_interval = poll;
    drive = &rig.add_device(c);
    sim = &rig.add_simulator(0, options);
    rig.start();
  }

  // Online: the ping (5.1) is answered and the line is idle.
  [[nodiscard]] bool ready() {
    return rig.run_until([&] { return drive->online(); }, 1s);
  }
  // "Run forward at `rpm`" in one request, as a PLC writes it, confirmed, then the 3.0 s ramp.
  [[nodiscard]] bool running_at(std::uint16_t rpm, std::uint16_t command = cmd::run_forward) {
    if (!drive->online() && !ready()) return false;
    if (write({command, rpm}) != Exception::none) return false;
    rig.run_for(4s);
    return read("speed_rpm") == rpm;
  }
  // Runs until the next poll has been answered: the driver knows what the inverter reported, and
  // the line is idle for the poll interval.
  [[nodiscard]] bool after_next_poll() {
    const std::size_t polls = count(kPoll);
    if (!rig.run_until([&] { return count(kPoll) > polls; }, 2s)) return false;
    rig.run_for(60ms);  // the poll's echo and its 7-byte ACK at 4800 baud
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
  // A write to the adapter's holding point `name` (its registers as the PLC writes them).
  std::optional<Exception> write(std::string_view name, std::vector<std::uint16_t> values) {
    return rig.write_and_wait(*drive, Table::holding, address_of(name), std::move(values));
  }
  std::shared_ptr<test::WriteOutcome> start_write(std::string_view name,
                                                  std::vector<std::uint16_t> values) {
    return rig.write(*drive, Table::holding, address_of(name), std::move(values));
  }
  [[nodiscard]] std::uint16_t address_of(std::string_view name) const {
    const MappedPoint* p = drive->map().find(name);
    EXPECT_NE(p, nullptr) << name;
    return p == nullptr ? 0xFFFF : p->address;
  }

  // A point's registers as a PLC reads them (u16 points, and u32 ones high word first).
  std::uint32_t read(std::string_view point) {
    const auto regs = rig.read(*drive, point);
    if (regs.size() == 2) return (std::uint32_t{regs[0]} << 16) | regs[1];
    return regs.empty() ? 0xFFFFFFFFu : regs[0];
  }
  std::uint32_t status() { return read("status"); }

  // Frames on the wire, resends included, from `from` on.
  [[nodiscard]] std::vector<Bytes> frames(TimePoint from = {}) const {
    std::vector<Bytes> out;
    for (const auto& f : rig.sent()) {
      if (f.at >= from) out.push_back(f.bytes);
    }
    return out;
  }
  // Frames on the wire after the first `mark` ones.
  [[nodiscard]] std::vector<Bytes> frames_after(std::size_t mark) const {
    std::vector<Bytes> out;
    for (std::size_t i = mark; i < rig.sent().size(); ++i) out.push_back(rig.sent()[i].bytes);
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
  [[nodiscard]] bool sim_says(std::string_view key_value) {
    return control("state").find(key_value) != std::string::npos;
  }

  test::BusRig rig;
  Device* drive = nullptr;
  Simulator* sim = nullptr;
};

}  // namespace drivegate::nidec
