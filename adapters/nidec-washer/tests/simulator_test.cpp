// The simulated inverter, made by the adapter's own factory and driven byte by byte like a
// master on the wire would, and its operator commands.
#include "simulator.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <utility>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "bench.h"  // kPoll, the document's poll frame (5.2)
#include "codec.h"

namespace drivegate::nidec::nidec_washer_simulator_test {
namespace {

using namespace std::chrono_literals;

const Bytes kNack = {0x5A, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0x5A};  // 5.16

class Sim : public ::testing::Test {
 protected:
  Bytes send(const Bytes& frame) { return sim.on_receive(frame, now); }
  void wait(Millis m) {
    for (const TimePoint end = now + m; now < end; now += 50ms) sim.on_tick(now);
  }
  std::string state() { return sim.control("state", now); }
  bool has(const std::string& kv) { return state().find(kv) != std::string::npos; }

  std::unique_ptr<Simulator> owned = test::make_simulator(drivegate_adapter);
  Simulator& sim = *owned;
  TimePoint now = TimePoint{} + 1h;
};

TEST_F(Sim, AnswersPingAndPoll_5_1_5_2) {
  EXPECT_EQ(send(encode(make_ping(7, 0))), (Bytes{0xA5, 0x02, 0x07, 0x01, 0x07, 0x00, 0xA6}));
  EXPECT_EQ(send(kPoll), (Bytes{0xA5, 0x05, 0x00, 0x00, 0x00, 0x00, 0xA0}));
  EXPECT_TRUE(has("pinged=1"));
}

TEST_F(Sim, ByteByByteAndTwoFramesInOneChunk) {
  const Bytes ping = encode(make_ping(7, 0));
  Bytes out;
  for (std::size_t i = 0; i < ping.size(); ++i) {
    const Bytes r = sim.on_receive(ByteView(ping).subspan(i, 1), now);
    if (i + 1 < ping.size()) {
      EXPECT_TRUE(r.empty()) << i;
    }
    out.insert(out.end(), r.begin(), r.end());
  }
  EXPECT_EQ(out.size(), 7u);
  Bytes two = kPoll;
  two.insert(two.end(), kPoll.begin(), kPoll.end());
  EXPECT_EQ(send(two).size(), 14u);
}

TEST_F(Sim, NackOnBadXorAndOnRemovedClutching_5_16) {
  Bytes bad = kPoll;
  bad[10] = 0xA1;
  EXPECT_EQ(send(bad), kNack);
  EXPECT_EQ(send(encode(Request{static_cast<Mode>(0x19), {1}})), kNack);
  EXPECT_EQ(send(kPoll).size(), 7u);  // back in step
}

TEST_F(Sim, NoiseBeforeAFrameIsSkipped) {
  Bytes wire = {0x00, 0x42};
  wire.insert(wire.end(), kPoll.begin(), kPoll.end());
  EXPECT_EQ(send(wire).size(), 7u);
}

TEST_F(Sim, PartialFrameIsDroppedAfterAPause) {
  EXPECT_TRUE(sim.on_receive(ByteView(kPoll).first(5), now).empty());
  now += 200ms;
  EXPECT_EQ(send(kPoll).size(), 7u);
}

TEST_F(Sim, NoMotionBeforePing_5_1) {
  send(encode(make_run(Mode::cw, 800, 0)));
  wait(500ms);
  EXPECT_TRUE(has("motion=stopped"));
  send(encode(make_ping(7, 0)));
  send(encode(make_run(Mode::cw, 800, 0)));
  wait(100ms);
  EXPECT_TRUE(has("motion=cw"));
  EXPECT_TRUE(has("speed_rpm=800"));
}

// 5.3 to 5.6 and 5.14: each rotation mode starts the motion of its own name.
TEST_F(Sim, EachRotationModeStartsItsOwnMotion) {
  send(encode(make_ping(7, 0)));
  const std::pair<Request, std::string> cases[] = {
      {make_run(Mode::cw, 800, 0), "motion=cw "},
      {make_run(Mode::ccw, 800, 0), "motion=ccw "},
      {make_agitation(800, {.cw_on = 10, .ccw_on = 10}), "motion=agitation "},
      {make_run(Mode::spin, 800, 0), "motion=spin "},
      {make_run(Mode::free_shaft_spin, 800, 0), "motion=free_shaft_spin "},
  };
  for (const auto& [request, motion] : cases) {
    SCOPED_TRACE(motion);
    send(encode(request));
    EXPECT_TRUE(has(motion)) << state();
  }
}

TEST_F(Sim, RampsWithTheAccelTime_5_6) {
  send(encode(make_ping(7, 0)));
  send(encode(make_run(Mode::spin, 1000, 20)));  // 2.0 s
  wait(1000ms);
  const Bytes r = send(kPoll);
  const int rpm = (r[3] << 8) | r[4];
  EXPECT_NEAR(rpm, 500, 30);
}

TEST_F(Sim, StopsTheMotorAfter6sOfBusSilence_section7) {
  send(encode(make_ping(7, 0)));
  send(encode(make_run(Mode::cw, 800, 0)));
  for (int i = 0; i < 20; ++i) {  // polled every 500 ms: keeps running
    wait(500ms);
    send(kPoll);
  }
  EXPECT_TRUE(has("motion=cw"));
  wait(6100ms);
  EXPECT_TRUE(has("motion=stopped"));
  EXPECT_TRUE(has("comm_fault=1"));
  EXPECT_TRUE(has("pinged=0"));
}

TEST_F(Sim, FaultsStopTheMotorAndClear_section8) {
  send(encode(make_ping(7, 0)));
  send(encode(make_run(Mode::cw, 800, 0)));
  EXPECT_EQ(sim.control("fault stall", now), "ok faults=0x08");
  EXPECT_EQ(sim.control("fault general", now), "ok faults=0x09");
  const Bytes r = send(kPoll);
  EXPECT_EQ(r[2], 0x09);
  EXPECT_EQ(r[4], 0x00);
  EXPECT_TRUE(has("motion=stopped"));
  // Motion is refused while faulted: the ACK carries the Error bits.
  EXPECT_EQ(send(encode(make_run(Mode::cw, 800, 0)))[2], 0x09);
  wait(4100ms);
  EXPECT_EQ(send(kPoll)[2], 0x01);  // general: kept until power off
  EXPECT_EQ(sim.control("clear", now), "ok faults=0x00");
  EXPECT_EQ(send(kPoll)[2], 0x00);
  sim.control("fault motor_over_temperature", now);
  wait(5s);
  EXPECT_EQ(send(kPoll)[2], 0x80);
  wait(16s);
  EXPECT_EQ(send(kPoll)[2], 0x00);
}

TEST_F(Sim, SilentAndCorrupt) {
  EXPECT_EQ(sim.control("silent on", now), "ok silent=1");
  EXPECT_TRUE(send(kPoll).empty());
  sim.control("silent off", now);
  sim.control("corrupt 1", now);
  Bytes r = send(kPoll);
  EXPECT_EQ(r.back(), 0xA0 ^ 0xFF);
  EXPECT_EQ(send(kPoll).back(), 0xA0);
  sim.control("nack 2", now);
  EXPECT_EQ(send(kPoll), kNack);
  EXPECT_EQ(send(kPoll), kNack);
  EXPECT_EQ(send(kPoll).size(), 7u);
}

TEST_F(Sim, FctReplyIsThirteenBytes_5_15) {
  const Bytes r = send(encode(make_fct()));
  ASSERT_EQ(r.size(), 13u);
  EXPECT_EQ(r[1], 0x66);
  const Decoded<Reply> d = decode_reply(r);
  EXPECT_EQ(d.status, DecodeStatus::frame);
}

TEST_F(Sim, HelpListsTheCommands) {
  const std::string h = sim.control("help", now);
  EXPECT_EQ(h.rfind("commands: ", 0), 0u);
  for (const char* c : {"state", "fault", "clear", "silent on|off", "corrupt N", "nack N", "load N",
                        "bus V", "fabric N", "version N"}) {
    EXPECT_NE(h.find(c), std::string::npos) << c;
  }
}

TEST_F(Sim, LoadFabricAndVersionShowInTheirAcks_5_1_5_10_5_11) {
  EXPECT_EQ(sim.control("version 0x0203", now), "ok version=0x0203");
  EXPECT_EQ(send(encode(make_ping(7, 0))), encode_reply(Mode::ping, {7, 0x02, 0x03, 0}));
  EXPECT_EQ(sim.control("load 40", now), "ok load=40");
  send(encode(make_bare(Mode::weight_detection)));  // 5.10: done in about 35 s
  wait(36s);
  const Decoded<Reply> w = decode_reply(send(encode(make_bare(Mode::weight_detection))));
  ASSERT_EQ(w.status, DecodeStatus::frame);
  EXPECT_EQ(w.frame.u16(1), 1800);  // the simulator's table: 1000 + 20 per 100 g
  EXPECT_EQ(w.frame.data[3], 40);
  EXPECT_EQ(sim.control("fabric 3", now), "ok fabric=3");
  const Decoded<Reply> f = decode_reply(send(encode(make_bare(Mode::fabric_detection))));
  EXPECT_EQ(f.frame.data[1], 3);
  EXPECT_EQ(sim.control("load 256", now).rfind("error: ", 0), 0u);
}

TEST_F(Sim, ControlAnswersUnknownCommandsWithTheList) {
  const std::string e = sim.control("dance", now);
  EXPECT_EQ(e.rfind("error: ", 0), 0u);
  EXPECT_NE(e.find("silent on|off"), std::string::npos);
  EXPECT_EQ(sim.control("fault nonsense", now).rfind("error: ", 0), 0u);
  EXPECT_EQ(sim.control("corrupt x", now).rfind("error: ", 0), 0u);
  EXPECT_EQ(sim.control("", now).rfind("error: ", 0), 0u);
  EXPECT_EQ(sim.control("bus 230", now), "ok dc_bus=230");
  const Bytes v = send(encode(make_bare(Mode::voltage_detection)));
  EXPECT_EQ((v[3] << 8) | v[4], 230);
}

}  // namespace
}  // namespace drivegate::nidec::nidec_washer_simulator_test
