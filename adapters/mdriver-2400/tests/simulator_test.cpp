// The simulator follows the document: check, run data, ramp, 6 s trip, silence on bad frames.
#include "drivegate/simulator.h"

#include <gtest/gtest.h>

#include <memory>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "codec.h"

namespace drivegate::mdriver::mdriver_2400_simulator_test {
namespace {

using namespace std::chrono_literals;

const TimePoint t0 = TimePoint{} + 1h;
const Bytes kCheck{0x00, 0x01, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x38};
const Bytes kCheckEcho{0x01, 0x00, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x38};
const Bytes kCheckZeros{0x01, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x00, 0x51};

struct SimRig {
  // The simulator the adapter's own factory makes, default options, at address 01.
  std::unique_ptr<Simulator> made = test::make_simulator(drivegate_adapter, 0x01);
  Simulator& sim = *made;
  TimePoint now = t0;
  void tick(Millis span) {
    const TimePoint end = now + span;
    while (now < end) {
      now += 10ms;
      sim.on_tick(now);
    }
  }
  Bytes send(const Bytes& b) { return sim.on_receive(b, now); }
  RunReply run(std::uint8_t code) {
    const Bytes reply = send(encode_run(0x00, 0x01, code, kChangeNormal));
    const auto d = decode(reply);
    EXPECT_EQ(d.status, DecodeStatus::frame);
    EXPECT_EQ(d.consumed, reply.size());
    return parse_run_reply(d.frame).value_or(RunReply{});
  }
  std::string state() { return sim.control("state", now); }
};

TEST(MdriverSim, AnswersTheFixedCode) {
  SimRig s;
  EXPECT_EQ(s.send(kCheck), kCheckEcho);
}

TEST(MdriverSim, AnswersZerosOnEepromFailureOrWrongCode) {
  SimRig s;
  s.sim.control("eeprom fail", s.now);
  EXPECT_EQ(s.send(kCheck), kCheckZeros);
  EXPECT_TRUE(s.send(encode_run(0x00, 0x01, 0x40, kChangeNormal)).empty());
  SimRig w;
  const Bytes wrong = encode({0x00, 0x01, 0x00, {0x01, 0x12, 0x00, 0x07}});
  EXPECT_EQ(w.send(wrong), kCheckZeros);
}

TEST(MdriverSim, IgnoresRunDataBeforeTheCheck) {
  SimRig s;
  EXPECT_TRUE(s.send(encode_run(0x00, 0x01, 0x40, kChangeNormal)).empty());
  s.send(kCheck);
  EXPECT_FALSE(s.send(encode_run(0x00, 0x01, 0x40, kChangeNormal)).empty());
}

TEST(MdriverSim, RunReplyBytes) {
  SimRig s;
  s.send(kCheck);
  // Section 3 No.2: R4 echoes the target, R5 actual (still 0), R8 IPM 1A = 26 deg C.
  const Bytes reply = s.send(Bytes{0x00, 0x01, 0x10, 0x02, 0x1C, 0x01, 0x00, 0x25});
  const Bytes expected{0x01, 0x00, 0x10, 0x07, 0x1C, 0x00, 0x00,
                       0x00, 0x1A, 0x00, 0x00, 0x00, 0x07};
  EXPECT_EQ(reply, expected);
  EXPECT_EQ(reply.back(), checksum(ByteView(reply).first(reply.size() - 1)));
}

TEST(MdriverSim, AcceptsAnyChunking) {
  SimRig s;
  Bytes out;
  for (const auto b : kCheck) {
    const Bytes r = s.send(Bytes{b});
    out.insert(out.end(), r.begin(), r.end());
  }
  EXPECT_EQ(out, kCheckEcho);
  // Two frames in one chunk: two replies.
  Bytes two = kCheck;
  two.insert(two.end(), kCheck.begin(), kCheck.end());
  Bytes both = kCheckEcho;
  both.insert(both.end(), kCheckEcho.begin(), kCheckEcho.end());
  EXPECT_EQ(s.send(two), both);
}

TEST(MdriverSim, IgnoresMalformedFramesSilently) {
  SimRig s;
  Bytes bad = kCheck;
  bad.back() ^= 1;
  EXPECT_TRUE(s.send(bad).empty());                                             // checksum
  EXPECT_TRUE(s.send(encode_check(0x00, 0x02)).empty());                        // another driver
  EXPECT_TRUE(s.send(encode({0x00, 0x01, 0x00, {0x01, 0x12, 0x00}})).empty());  // length
  EXPECT_TRUE(s.send(Bytes{0x00, 0x01, 0x20, 0x00, 0x01, 0x33}).empty());       // command
  s.now += 200ms;  // a stale partial frame is dropped when the next one starts
  EXPECT_TRUE(s.send(Bytes{0x00, 0x01, 0x00}).empty());
  s.now += 200ms;
  EXPECT_EQ(s.send(kCheck), kCheckEcho);
  EXPECT_NE(s.state().find("frames=1"), std::string::npos);
}

TEST(MdriverSim, RampsAt360RpmPerSecond) {
  SimRig s;
  s.send(kCheck);
  s.run(0x40);
  s.tick(100ms);
  const int first = s.run(0x40).actual_code;
  EXPECT_GE(first, 0x1C);  // starts at the lowest running speed
  EXPECT_LE(first, 0x1E);
  s.tick(1000ms);
  EXPECT_EQ(s.run(0x40).actual_code - first, 20);  // 20 codes (360 rpm) a second
  s.tick(2000ms);
  EXPECT_EQ(s.run(0x40).actual_code, 0x40);
  s.run(0x01);
  s.tick(3000ms);
  EXPECT_EQ(s.run(0x01).actual_code, 0x00);
}

TEST(MdriverSim, TripsAfterSixSecondsWithoutAFrameAndResetsWithCode00) {
  SimRig s;
  s.send(kCheck);
  s.run(0x40);
  s.tick(5900ms);
  EXPECT_NE(s.state().find("error=0x00"), std::string::npos);
  s.tick(200ms);
  EXPECT_NE(s.state().find("error=0x0c"), std::string::npos);
  const RunReply r = s.run(0x40);
  EXPECT_EQ(r.error_code, 0x0C);
  s.tick(500ms);
  EXPECT_EQ(s.run(0x40).actual_code, 0x00);  // latched: stays stopped
  EXPECT_EQ(s.run(0x00).error_code, 0x00);   // [00]: error reset & stop
}

TEST(MdriverSim, ControlCommands) {
  SimRig s;
  s.send(kCheck);
  EXPECT_EQ(s.sim.control("fault ipm_over_temperature", s.now), "ok error=0x0e");
  EXPECT_EQ(s.run(0x40).error_code, 0x0E);
  EXPECT_EQ(s.sim.control("fault 0x03", s.now), "ok error=0x03");
  EXPECT_EQ(s.sim.control("fault stall", s.now), "ok error=0x04");  // unified alias too
  EXPECT_EQ(s.sim.control("fault drive_over_temperature", s.now), "ok error=0x0e");
  EXPECT_EQ(s.sim.control("clear", s.now), "ok");
  EXPECT_EQ(s.run(0x40).error_code, 0x00);
  EXPECT_EQ(s.sim.control("temp 80", s.now), "ok temp=80");
  EXPECT_EQ(s.sim.control("info 2 7", s.now), "ok");
  const RunReply r = s.run(0x40);
  EXPECT_EQ(r.ipm_temp_c, 80);
  EXPECT_EQ(r.info[1], 7);
  EXPECT_EQ(s.sim.control("corrupt 2", s.now), "ok corrupt=2");
  Bytes bad = s.send(kCheck);
  EXPECT_EQ(decode(bad).error, FrameError::bad_checksum);
  bad = s.send(kCheck);
  EXPECT_EQ(decode(bad).error, FrameError::bad_checksum);
  EXPECT_EQ(s.send(kCheck), kCheckEcho);
  s.sim.control("silent on", s.now);
  EXPECT_TRUE(s.send(kCheck).empty());
  s.sim.control("silent off", s.now);
  EXPECT_EQ(s.send(kCheck), kCheckEcho);
  EXPECT_EQ(s.sim.control("power-cycle", s.now), "ok");
  EXPECT_NE(s.state().find("checked=0"), std::string::npos);
  EXPECT_EQ(s.sim.control("bogus", s.now).rfind("error: ", 0), 0u);
  EXPECT_EQ(s.sim.control("fault nonsense", s.now).rfind("error: ", 0), 0u);
  EXPECT_EQ(s.sim.control("", s.now).rfind("error: ", 0), 0u);
}

TEST(MdriverSim, StateLineHasStableKeys) {
  SimRig s;
  const std::string st = s.state();
  for (const char* key : {"address=0x01", "checked=0", "eeprom=ok",
                          "target=", "change=", "actual=", "rpm=", "error=", "temp=26",
                          "info=", "silent=off", "corrupt=0", "frames=", "ignored="}) {
    EXPECT_NE(st.find(key), std::string::npos) << key;
  }
  EXPECT_EQ(st.find('\n'), std::string::npos);
}

}  // namespace
}  // namespace drivegate::mdriver::mdriver_2400_simulator_test
