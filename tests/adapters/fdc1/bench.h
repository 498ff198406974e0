// One FDC1 controller and its simulator on the real bus engine, simulated time and a simulated
// line (tests/support/bus_rig.h), both made by this adapter's own factories from options as text,
// and the frames of the document the tests expect on the wire.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "codec.h"
#include "gateway/value_codec.h"

namespace drivegate::fdc1 {

using namespace std::chrono_literals;
using modbus::Exception;

// INPUT, Programming speed (decimal 72 115 min max 85 x), slave mode: stop is minimum 0 (with
// the in-range maximum 3500), a run minimum = maximum = the setpoint.
inline const Bytes kStopFrame = {0x48, 0x73, 0x00, 0x00, 0x0D, 0xAC, 0x55, 0xCF};
inline const Bytes kRun2000 = {0x48, 0x73, 0x07, 0xD0, 0x07, 0xD0, 0x55, 0x6E};
inline const Bytes kRun2500 = {0x48, 0x73, 0x09, 0xC4, 0x09, 0xC4, 0x55, 0x6E};
inline const Bytes kRun3000 = {0x48, 0x73, 0x0B, 0xB8, 0x0B, 0xB8, 0x55, 0x6E};

// The common block (docs/register-map.md): holding registers command and setpoint_rpm, the
// values of command, and the bits of status.
inline constexpr std::uint16_t kCommandRegister = 0;
inline constexpr std::uint16_t kSetpointRegister = 1;
inline constexpr std::uint16_t kStop = 0, kRunForward = 1, kRunReverse = 2, kQuickStop = 3,
                               kResetFault = 4;
inline constexpr std::uint16_t kOnline = 1u << 0, kRunning = 1u << 1, kFaulted = 1u << 2,
                               kCommLost = 1u << 4, kCommandPending = 1u << 6;

// The options of a controller the gateway runs (slave mode); the default ones only monitor.
inline const test::OptionText kSlave = {{"slave_mode", "true"}};

// Time an n-byte frame takes on the 1200 8N1 line.
inline std::chrono::nanoseconds wire(std::size_t n) {
  return kCharacterTime * static_cast<long>(n);
}

struct Bench {
  explicit Bench(const test::OptionText& options = kSlave, bool maintenance = false,
                 Millis budget = Millis(1000))
      : rig(drivegate_adapter) {
    DeviceConfig c = rig.device_config("fridge", 0, options);
    c.budget = budget;
    drive = &rig.add_device(c, maintenance);
    sim = &rig.add_simulator(0, options);
    rig.start();
  }

  // Online (a first status heard), then the line idle again after the start-up frame.
  [[nodiscard]] bool heard() {
    if (!rig.run_until([&] { return drive->online(); }, 3s)) return false;
    rig.run_for(100ms);
    return true;
  }
  // Heard, then "run at `rpm`" in one request, as a PLC writes it, confirmed by the stream, and
  // the ramp given time to reach `rpm` (1000 rpm/s from 1500 in the simulator).
  [[nodiscard]] bool run_at(std::uint16_t rpm) {
    if (!heard()) return false;
    if (write({kRunForward, rpm}) != Exception::none) return false;
    rig.run_for(3s);
    return read("speed_rpm") == rpm;
  }
  // Runs until the device heard its next status frame.
  [[nodiscard]] bool next_status() {
    const std::uint32_t before = read("frames_good");
    return rig.run_until([&] { return read("frames_good") > before; }, 1s);
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
  // Engineering values written to consecutive adapter points from `first` on, in one request,
  // as the Modbus server (or `drivegate action`) makes it.
  std::shared_ptr<test::WriteOutcome> start_point_write(std::string_view first,
                                                        const std::vector<double>& values) {
    const MappedPoint* p = drive->map().find(first);
    EXPECT_NE(p, nullptr) << first;
    if (p == nullptr) return std::make_shared<test::WriteOutcome>();
    std::vector<std::uint16_t> regs;
    std::uint16_t address = p->address;
    for (const double v : values) {
      const MappedPoint* at = drive->map().at(Table::holding, address);
      EXPECT_NE(at, nullptr) << "no holding point at " << address;
      if (at == nullptr) break;
      std::vector<std::uint16_t> out(at->spec.register_count());
      encode_value(at->spec, Value{v}, out);
      regs.insert(regs.end(), out.begin(), out.end());
      address = static_cast<std::uint16_t>(address + out.size());
    }
    return rig.write(*drive, Table::holding, p->address, std::move(regs));
  }
  std::optional<Exception> write_point(std::string_view point, double value) {
    return rig.wait(start_point_write(point, {value}));
  }

  // A point's value as a PLC reads it (u16 points, and u32 ones high word first).
  std::uint32_t read(std::string_view point) {
    const auto regs = rig.read(*drive, point);
    if (regs.size() == 2) return (std::uint32_t{regs[0]} << 16) | regs[1];
    return regs.empty() ? 0xFFFFFFFFu : regs[0];
  }
  // A string point as a PLC reads it: two characters a register, the first in the high byte.
  std::string text(std::string_view point) {
    std::string out;
    for (const std::uint16_t r : rig.read(*drive, point)) {
      for (const auto c : {static_cast<char>(r >> 8), static_cast<char>(r & 0xFF)}) {
        if (c == '\0') return out;
        out.push_back(c);
      }
    }
    return out;
  }

  // Frames on the wire, from `from` on.
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
  [[nodiscard]] const Bytes& last() const { return rig.sent().back().bytes; }
  std::string control(std::string_view line) { return sim->control(line, rig.now()); }
  // Whether the simulator's `state` line holds `key_value` ("motor=on", "min=2000").
  bool sim_has(std::string_view key_value) {
    return (" " + control("state") + " ").find(" " + std::string(key_value) + " ") !=
           std::string::npos;
  }

  test::BusRig rig;
  Device* drive = nullptr;
  Simulator* sim = nullptr;
};

}  // namespace drivegate::fdc1
