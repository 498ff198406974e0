// The eDrive's frames as the tests build and decode them, and an eDrive on the shared bench
// (tests/support/adapter_bench.h): what its start-up and a run take, and the frames the master
// sent, decoded, with their times.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "driver.h"
#include "payloads.h"

namespace drivegate::unicla {

using namespace std::chrono_literals;
using namespace test::common_block;

// "Message IDs".
inline constexpr std::uint8_t kStatus = 0x01, kBuild = 0x02, kLimits = 0x03, kRunState = 0xC0,
                              kAck = 0xC1;
// "Commands".
inline constexpr std::uint8_t kRead = 0xC0, kWrite = 0xC1;
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

// A frame the master sent, and when its first byte went on the wire.
struct Sent {
  TimePoint at;
  Bytes bytes;
  Frame frame;
};
// Every frame the master sent on the rig's line from `from` on, resends included.
inline std::vector<Sent> sent_by_master(const test::BusRig& rig, TimePoint from) {
  std::vector<Sent> out;
  for (const auto& f : rig.sent()) {
    if (f.at >= from) out.push_back({f.at, f.bytes, decoded(f.bytes)});
  }
  return out;
}

struct Bench : test::AdapterBench {
  explicit Bench(const test::BenchSetup& setup = {}) : AdapterBench(drivegate_adapter, setup) {}

  // Online: build information, limits and the first status are in, and the line is idle.
  [[nodiscard]] bool ready() { return until_online(100ms); }
  // From ready (test::ReadyBench): "run at `rpm`" in one request, as a PLC writes it, confirmed,
  // then the ramp to that speed.
  [[nodiscard]] bool running_at(std::uint16_t rpm) {
    return run_forward_at(rpm) && until_reads("speed_rpm", rpm, 10s);
  }

  // Frames the master sent from `from` on, resends included, with message id `msg` if given.
  [[nodiscard]] std::vector<Sent> sent(TimePoint from = {},
                                       std::optional<std::uint8_t> msg = std::nullopt) const {
    std::vector<Sent> out;
    for (auto& s : sent_by_master(rig, from)) {
      if (!msg || s.frame.message_id == *msg) out.push_back(std::move(s));
    }
    return out;
  }
  [[nodiscard]] std::uint8_t last_sequence() const { return decoded(last()).sequence; }
};

}  // namespace drivegate::unicla
