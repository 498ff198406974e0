// The simulated eDrive: replies on the wire, chunked input, addressing, run state within its
// limits, fault injection, silence, corrupt CRCs and the operator commands.
#include "simulator.h"

#include <gtest/gtest.h>

#include <memory>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "faults.h"
#include "payloads.h"

namespace drivegate::unicla {
namespace {

const TimePoint t0 = TimePoint{} + std::chrono::hours(1);

// A simulator as `drivegate sim` makes one: the adapter's factory, options as text.
std::unique_ptr<Simulator> make(std::uint32_t address, const test::OptionText& options = {}) {
  return test::make_simulator(drivegate_adapter, address, options);
}

Bytes read_req(std::uint8_t dst, std::uint8_t id, std::uint8_t seq, std::uint8_t src = 0x00) {
  Frame f;
  f.source = src;
  f.destination = dst;
  f.command = 0xC0;
  f.message_id = id;
  f.sequence = seq;
  return encode(f);
}

Bytes write_req(std::uint8_t dst, std::uint8_t id, Bytes payload, std::uint8_t seq = 9) {
  Frame f;
  f.destination = dst;
  f.command = 0xC1;
  f.message_id = id;
  f.sequence = seq;
  f.payload = std::move(payload);
  return encode(f);
}

Frame reply_of(const Bytes& wire) {
  const auto d = decode(wire);
  EXPECT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.consumed, wire.size());
  return d.frame;
}

Status status_of(Simulator& sim, TimePoint now) {
  const Frame f = reply_of(sim.on_receive(read_req(1, 0x01, 1), now));
  return *parse_status(f.payload, ByteOrder::big);
}

void tick(Simulator& sim, TimePoint& now, Millis span) {
  const TimePoint end = now + span;
  while (now < end) {
    now += Millis(10);
    sim.on_tick(now);
  }
}

// "Examples / Status Read from Device Id 0x01": the request with the CRC example's sequence.
TEST(UniclaSimulator, AnswersTheDocumentsStatusRead) {
  const auto sim = make(1);
  const Bytes req = {0x7E, 0x00, 0x01, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0xA7, 0x70, 0x7E};
  const Frame f = reply_of(sim->on_receive(req, t0));
  // Reply header "0x01 0x00 0xC0 0x01 0xXX 0x00 0x00 0x40", 64 bytes.
  EXPECT_EQ(f.source, 0x01);
  EXPECT_EQ(f.destination, 0x00);
  EXPECT_EQ(f.command, 0xC0);
  EXPECT_EQ(f.message_id, 0x01);
  EXPECT_EQ(f.sequence, 0x36);
  EXPECT_EQ(f.payload.size(), 0x40u);
  EXPECT_EQ(f.payload,
            encode_status(dynamic_cast<EDriveSimulator&>(*sim).status(), ByteOrder::big));
}

TEST(UniclaSimulator, BuffersRequestsSplitAtEveryByte) {
  const Bytes req = read_req(1, 0x02, 0x44);
  for (std::size_t split = 1; split < req.size(); ++split) {
    const auto sim = make(1);
    EXPECT_TRUE(sim->on_receive(ByteView(req).first(split), t0).empty()) << split;
    const Frame f = reply_of(sim->on_receive(ByteView(req).subspan(split), t0));
    EXPECT_EQ(f.message_id, 0x02);
    EXPECT_EQ(f.payload.size(), kBuildInfoSize);
  }
}

TEST(UniclaSimulator, AnswersOnlyItsOwnIdAndTheGlobalAddress) {
  const auto sim = make(7);
  EXPECT_TRUE(sim->on_receive(read_req(1, 0x01, 1), t0).empty());
  EXPECT_TRUE(sim->on_receive(read_req(7, 0x01, 1, 0x03), t0).empty());  // not from the master
  EXPECT_TRUE(sim->on_receive(read_req(7, 0x09, 1), t0).empty());        // unknown message
  const Frame own = reply_of(sim->on_receive(read_req(7, 0x03, 2), t0));
  EXPECT_EQ(own.source, 7);
  EXPECT_EQ(parse_running_limits(own.payload, ByteOrder::big)->device_id, 7);
  // "all devices will reply (if needed) with their individual device ids in the header"
  const Frame global = reply_of(sim->on_receive(read_req(0xFF, 0x01, 3), t0));
  EXPECT_EQ(global.source, 7);
  EXPECT_EQ(global.sequence, 3);
}

TEST(UniclaSimulator, IgnoresBadCrcAndSkipsNoise) {
  const auto sim = make(1);
  Bytes bad = read_req(1, 0x01, 1);
  bad[bad.size() - 2] ^= 0x01;
  EXPECT_TRUE(sim->on_receive(bad, t0).empty());
  Bytes noisy = {0x55, 0xAA};
  const Bytes good = read_req(1, 0x01, 2);
  noisy.insert(noisy.end(), good.begin(), good.end());
  EXPECT_EQ(reply_of(sim->on_receive(noisy, t0)).sequence, 2);
}

TEST(UniclaSimulator, FollowsRunStateWithinLimits) {
  const auto sim = make(1);
  TimePoint now = t0;
  sim->on_tick(now);
  EXPECT_EQ(status_of(*sim, now).op_state, 3);                                  // Stopped
  EXPECT_TRUE(sim->on_receive(write_req(1, 0xC0, {0x1B, 0x58}), now).empty());  // 7000: ignored
  EXPECT_EQ(status_of(*sim, now).op_state, 3);
  EXPECT_TRUE(sim->on_receive(write_req(1, 0xC0, {0x0B, 0xB8}), now).empty());  // 3000, no ack
  EXPECT_EQ(status_of(*sim, now).op_state, 1);                                  // Starting
  tick(*sim, now, Millis(4000));
  Status s = status_of(*sim, now);
  EXPECT_EQ(s.op_state, 2);  // Running
  EXPECT_EQ(s.rpm, 3000);
  EXPECT_GT(s.discharge_pressure, s.suction_pressure);
  EXPECT_GT(s.watts, 0);
  sim->on_receive(write_req(1, 0xC0, {0x00, 0x00}), now);
  EXPECT_EQ(status_of(*sim, now).op_state, 3);
  tick(*sim, now, Millis(2000));
  EXPECT_EQ(status_of(*sim, now).rpm, 0);
}

TEST(UniclaSimulator, FaultsFlagsAcknowledgeAndSticky) {
  const auto sim = make(1);
  EXPECT_EQ(sim->control("fault startup", t0).rfind("ok", 0), 0u);
  Status s = status_of(*sim, t0);
  EXPECT_EQ(s.op_state, 7);
  EXPECT_EQ(s.motor_run_flags, 1u << 12);
  EXPECT_TRUE(map_faults(s).faults.has(Fault::stall));
  sim->on_receive(write_req(1, 0xC0, {0x0B, 0xB8}), t0);  // refused while faulted
  EXPECT_EQ(status_of(*sim, t0).op_state, 7);
  sim->control("sticky on", t0);
  sim->on_receive(write_req(1, 0xC1, {}), t0);
  EXPECT_EQ(status_of(*sim, t0).op_state, 7);
  sim->control("sticky off", t0);
  sim->on_receive(write_req(1, 0xC1, {}), t0);
  s = status_of(*sim, t0);
  EXPECT_EQ(s.op_state, 3);
  EXPECT_EQ(s.motor_run_flags, 0);

  sim->control("fault electrical", t0);
  s = status_of(*sim, t0);
  EXPECT_EQ(s.op_state, 9);
  EXPECT_EQ(s.electrical_flags, 1u << 16);
  sim->control("clear", t0);
  EXPECT_EQ(status_of(*sim, t0).op_state, 3);

  sim->control("fault 12", t0);  // raw op state: Locked
  EXPECT_EQ(status_of(*sim, t0).op_state, 12);
  sim->control("clear", t0);
  sim->control("flags compressor_run 0x4000", t0);
  s = status_of(*sim, t0);
  EXPECT_EQ(s.compressor_run_flags, 0x4000);
  EXPECT_EQ(s.op_state, 3);
  EXPECT_TRUE(map_faults(s).warning);
  sim->control("flags electrical 0x1FFFFFF", t0);
  EXPECT_EQ(status_of(*sim, t0).electrical_flags, 0xFFFFFFu);
}

TEST(UniclaSimulator, SilentAndCorrupt) {
  const auto sim = make(1);
  sim->control("silent on", t0);
  EXPECT_TRUE(sim->on_receive(read_req(1, 0x01, 1), t0).empty());
  sim->control("silent off", t0);
  sim->control("corrupt 2", t0);
  for (int i = 0; i < 2; ++i) {
    const auto d = decode(sim->on_receive(read_req(1, 0x01, 2), t0));
    ASSERT_EQ(d.status, DecodeStatus::bad);
    EXPECT_EQ(d.error, FrameError::bad_checksum);
  }
  EXPECT_EQ(decode(sim->on_receive(read_req(1, 0x01, 3), t0)).status, DecodeStatus::frame);
}

TEST(UniclaSimulator, ControlDisabledIgnoresWritesAndLimitsCommand) {
  const auto sim = make(1);
  sim->control("control off", t0);
  sim->on_receive(write_req(1, 0xC0, {0x0B, 0xB8}), t0);
  EXPECT_EQ(status_of(*sim, t0).op_state, 3);
  const Frame lim = reply_of(sim->on_receive(read_req(1, 0x03, 1), t0));
  EXPECT_EQ(parse_running_limits(lim.payload, ByteOrder::big)->control_enabled, 0);
  sim->control("control on", t0);
  EXPECT_EQ(sim->control("limits 2000 5000", t0).rfind("ok", 0), 0u);
  const Frame lim2 = reply_of(sim->on_receive(read_req(1, 0x03, 2), t0));
  EXPECT_EQ(parse_running_limits(lim2.payload, ByteOrder::big)->max_speed, 5000);
}

TEST(UniclaSimulator, StateLineAndErrors) {
  const auto sim = make(4);
  const std::string st = sim->control("state", t0);
  for (const char* key : {"address=4", "op_state=3", "op_state_name=stopped", "rpm=0", "min=1500",
                          "max=6000", "control=on", "silent=off", "corrupt=0"}) {
    EXPECT_NE(st.find(key), std::string::npos) << key << " in " << st;
  }
  EXPECT_EQ(sim->control("help", t0).rfind("commands:", 0), 0u);
  for (const char* bad : {"bogus", "fault nosuch", "silent maybe", "corrupt x", "limits 5 1", "",
                          "limits 0 70000", "fault 256", "help me"}) {
    const std::string r = sim->control(bad, t0);
    EXPECT_EQ(r.rfind("error:", 0), 0u) << bad;
    EXPECT_NE(r.find("commands:"), std::string::npos) << bad;
  }
}

TEST(UniclaSimulator, LittleEndianFloats) {
  const auto sim = make(1, {{"byte_order", "little"}});
  const Frame f = reply_of(sim->on_receive(read_req(1, 0x01, 1), t0));
  EXPECT_FLOAT_EQ(parse_status(f.payload, ByteOrder::little)->suction_pressure, 4.5F);
  // 4.5f = 0x40900000, little-endian: 00 00 90 40.
  EXPECT_EQ(Bytes(f.payload.begin(), f.payload.begin() + 4), (Bytes{0x00, 0x00, 0x90, 0x40}));
}

}  // namespace
}  // namespace drivegate::unicla
