// eDrives and their simulators on the real bus engine, simulated time and a simulated line
// (tests/support/bus_rig.h), made by this adapter's own factories from options as text, and
// what a PLC sees of them: the frames on the wire, decoded, with their times; registers read as a
// PLC reads them; writes made as the Modbus server makes them.
#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "codec.h"
#include "driver.h"
#include "payloads.h"

namespace drivegate::unicla {

using namespace std::chrono_literals;
using modbus::Exception;

// "Message IDs".
inline constexpr std::uint8_t kStatus = 0x01, kBuild = 0x02, kLimits = 0x03, kRunState = 0xC0,
                              kAck = 0xC1;
// "Commands".
inline constexpr std::uint8_t kRead = 0xC0, kWrite = 0xC1;

// The common block (docs/register-map.md): holding registers command and setpoint_rpm, the
// values of command, and the bits of status.
inline constexpr std::uint16_t kCommandRegister = 0;
inline constexpr std::uint16_t kSetpointRegister = 1;
inline constexpr std::uint16_t kStop = 0, kRunForward = 1, kRunReverse = 2, kQuickStop = 3,
                               kResetFault = 4;
inline constexpr std::uint16_t kOnline = 1u << 0, kRunning = 1u << 1, kFaulted = 1u << 2,
                               kWarning = 1u << 3, kCommLost = 1u << 4, kCommandPending = 1u << 6;
// ED_OP_STATE values ("Interpretation of consolidated data").
inline constexpr std::uint32_t kStarting = 1, kRunningState = 2, kStopped = 3, kFaultMotor = 7;

// A frame the master sends: `msg` to drive `dst` with sequence `seq` ("Message Structure").
inline Bytes master_frame(std::uint8_t dst, std::uint8_t cmd, std::uint8_t msg, std::uint8_t seq,
                          Bytes payload = {}) {
  Frame f;
  f.source = kMasterAddress;
  f.destination = dst;
  f.command = cmd;
  f.message_id = msg;
  f.sequence = seq;
  f.payload = std::move(payload);
  return encode(f);
}
// "Set Run State": u16 speed, high byte first ("Examples": 1000 rpm = 03 E8).
inline Bytes run_state_frame(std::uint8_t dst, std::uint8_t seq, std::uint16_t rpm) {
  return master_frame(dst, kWrite, kRunState, seq, {hi8(rpm), lo8(rpm)});
}

// A whole frame on the wire, decoded: every frame either side sends must be one.
inline Frame decoded(const Bytes& wire) {
  const auto d = decode(wire);
  EXPECT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.consumed, wire.size());
  return d.frame;
}

// Time `n` characters take on the line.
inline std::chrono::nanoseconds wire_time(std::size_t n) {
  return kCharacterTime * static_cast<long>(n);
}

// A point's value as a PLC reads it: u16 points, u32 ones high word first.
inline std::uint32_t value_of(test::BusRig& rig, Device& d, std::string_view point) {
  const auto regs = rig.read(d, point);
  if (regs.size() == 2) return (std::uint32_t{regs[0]} << 16) | regs[1];
  return regs.empty() ? 0xFFFFFFFFu : regs[0];
}
// A string point: two characters a register, high byte first, cut at the first NUL.
inline std::string text_of(test::BusRig& rig, Device& d, std::string_view point) {
  std::string s;
  for (const std::uint16_t w : rig.read(d, point)) {
    for (const int c : {w >> 8, w & 0xFF}) {
      if (c == 0) return s;
      s.push_back(static_cast<char>(c));
    }
  }
  return s;
}

// A frame the master sent, and when its first byte went on the wire.
struct Sent {
  TimePoint at;
  Bytes bytes;
  Frame frame;
};

struct Bench {
  // One drive at `address` and its simulator, with the same options, on a line of its own.
  explicit Bench(const test::OptionText& options = {}, Millis poll = 500ms,
                 std::uint32_t address = 1)
      : Bench(options, options, poll, address) {}
  Bench(const test::OptionText& options, const test::OptionText& sim_options, Millis poll,
        std::uint32_t address)
      : rig(drivegate_adapter) {
    DeviceConfig c = rig.device_config("edrive", address, options);
    c.poll_interval = poll;
    drive = &rig.add_device(c);
    sim = &rig.add_simulator(address, sim_options);
    rig.start();
  }

  // Online: build information, limits and the first status are in, and the line is idle.
  [[nodiscard]] bool ready() {
    if (!rig.run_until([&] { return drive->online(); }, 3s)) return false;
    rig.run_for(100ms);
    return true;
  }
  // "Run at `rpm`" in one request, as a PLC writes it, confirmed, then the ramp to that speed.
  [[nodiscard]] bool running_at(std::uint16_t rpm) {
    if (!ready()) return false;
    if (write({kRunForward, rpm}) != Exception::none) return false;
    return rig.run_until([&] { return read("speed_rpm") == rpm; }, 10s);
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

  std::uint32_t read(std::string_view point) { return value_of(rig, *drive, point); }
  float read_f32(std::string_view point) { return std::bit_cast<float>(read(point)); }
  std::string read_text(std::string_view point) { return text_of(rig, *drive, point); }

  // Frames the master sent from `from` on, resends included, with message id `msg` if given.
  [[nodiscard]] std::vector<Sent> sent(TimePoint from = {},
                                       std::optional<std::uint8_t> msg = std::nullopt) const {
    std::vector<Sent> out;
    for (const auto& f : rig.sent()) {
      if (f.at < from) continue;
      Sent s{f.at, f.bytes, decoded(f.bytes)};
      if (!msg || s.frame.message_id == *msg) out.push_back(std::move(s));
    }
    return out;
  }
  [[nodiscard]] std::uint8_t last_sequence() const {
    return decoded(rig.sent().back().bytes).sequence;
  }
  std::string control(std::string_view line) { return sim->control(line, rig.now()); }

  test::BusRig rig;
  Device* drive = nullptr;
  Simulator* sim = nullptr;
};

}  // namespace drivegate::unicla
