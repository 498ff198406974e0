// The simulated controller on its own, as `drivegate sim` hosts it (made by the adapter's own
// factory from options as text): the stream, slave-mode speed, the 60 s watchdog, the
// programming echo, and the operator commands.
#include "simulator.h"

#include <gtest/gtest.h>

#include "adapter_factories.h"
#include "bench.h"
#include "codec.h"

namespace drivegate::fdc1 {
namespace {

struct SimRig {
  explicit SimRig(bool slave = true)
      : sim(test::make_simulator(drivegate_adapter, 0,
                                 {{"slave_mode", slave ? "true" : "false"}})) {}
  // Ticks every 10 ms for `span`, collecting what the simulator sends.
  Bytes run(Millis span) {
    Bytes out;
    const TimePoint end = now + span;
    while (now < end) {
      now += 10ms;
      const Bytes b = sim->on_tick(now);
      out.insert(out.end(), b.begin(), b.end());
    }
    return out;
  }
  std::vector<Status> statuses(Millis span) {
    const Bytes wire = run(span);
    std::vector<Status> out;
    std::size_t at = 0;
    while (at < wire.size()) {
      const auto d = decode_device(ByteView(wire).subspan(at));
      if (d.status == DecodeStatus::incomplete) break;
      if (d.status == DecodeStatus::frame) out.push_back(std::get<Status>(d.frame));
      at += d.consumed;
    }
    return out;
  }
  std::string control(std::string_view line) { return sim->control(line, now); }
  bool has(std::string_view kv) { return control("state").find(kv) != std::string::npos; }

  std::unique_ptr<Simulator> sim;
  TimePoint now = TimePoint{} + 1h;
};

TEST(Fdc1Simulator, StreamsTheOffFormEveryHalfSecond) {
  SimRig rig;
  const Bytes wire = rig.run(5000ms);
  ASSERT_EQ(wire.size(), 10 * kStatusSize);  // OUTPUT: every 0.5 s
  EXPECT_EQ(Bytes(wire.begin(), wire.begin() + 8),
            (Bytes{0x1B, 0x4C, 0x00, 0x00, 0x00, 0x00, 0x1B, 0x4C}));
}

TEST(Fdc1Simulator, FollowsSlaveModeSpeedAndStreamsTheOnForm) {
  SimRig rig;
  rig.run(100ms);
  EXPECT_TRUE(rig.sim->on_receive(kRun2000, rig.now).empty());  // never acknowledged
  const auto s = rig.statuses(3s);
  ASSERT_FALSE(s.empty());
  EXPECT_TRUE(s.back().motor_on);
  EXPECT_EQ(s.back().rpm, 2000);
  EXPECT_NEAR(s.back().current_a(), 2.4, 0.001);
  rig.sim->on_receive(kStopFrame, rig.now);
  const auto stopped = rig.statuses(1s);
  EXPECT_FALSE(stopped.back().motor_on);
  EXPECT_TRUE(rig.has("speeds=2"));
}

TEST(Fdc1Simulator, AcceptsSpeedFramesInAnyChunks) {
  SimRig rig;
  rig.run(100ms);
  for (const auto b : kRun3000) rig.sim->on_receive(ByteView(&b, 1), rig.now);
  EXPECT_TRUE(rig.has("min=3000"));
}

TEST(Fdc1Simulator, StopsAfter60sWithoutARefresh) {
  SimRig rig;
  rig.run(100ms);
  rig.sim->on_receive(kRun2000, rig.now);
  rig.run(59s);
  EXPECT_TRUE(rig.has("motor=on"));
  rig.run(2s);
  EXPECT_TRUE(rig.has("motor=off"));
  EXPECT_TRUE(rig.has("watchdog=1"));
  rig.sim->on_receive(kRun2000, rig.now);  // a new speed starts it again
  rig.run(1s);
  EXPECT_TRUE(rig.has("motor=on"));
}

TEST(Fdc1Simulator, WindowShortensTheWatchdogForTests) {
  SimRig rig;
  EXPECT_TRUE(rig.has("window_s=60"));
  EXPECT_EQ(rig.control("window 0").rfind("error:", 0), 0u);
  EXPECT_EQ(rig.control("window 61").rfind("error:", 0), 0u);
  EXPECT_EQ(rig.control("window x").rfind("error:", 0), 0u);
  ASSERT_EQ(rig.control("window 5"), "ok");
  rig.run(100ms);
  rig.sim->on_receive(kRun2000, rig.now);
  rig.run(4s);
  rig.sim->on_receive(kRun2000, rig.now);  // a refresh inside the window
  rig.run(4s);
  EXPECT_TRUE(rig.has("motor=on"));
  rig.run(2s);  // 6 s since the last frame
  EXPECT_TRUE(rig.has("motor=off"));
  EXPECT_TRUE(rig.has("watchdog=1"));
}

TEST(Fdc1Simulator, EchoesProgrammingWith27And80) {
  SimRig rig;
  rig.run(100ms);
  const Program p{2000, 3000, 0, 2, {12464, 14838, 24927, 29675, 42732, 52228}};
  const Bytes frame = encode_program(p);
  Bytes echo;
  for (std::size_t i = 0; i < frame.size(); ++i) {  // byte by byte
    const Bytes b = rig.sim->on_receive(ByteView(frame).subspan(i, 1), rig.now);
    echo.insert(echo.end(), b.begin(), b.end());
  }
  Bytes want = frame;
  want[0] = 27;
  EXPECT_EQ(echo, want);
  EXPECT_TRUE(rig.has("programs=1"));
}

TEST(Fdc1Simulator, IgnoresBadChecksumsAndStaleFragments) {
  SimRig rig;
  rig.run(100ms);
  Bytes bad = kRun2000;
  bad[7] ^= 1;
  rig.sim->on_receive(bad, rig.now);
  EXPECT_TRUE(rig.has("rejected=1"));
  EXPECT_TRUE(rig.has("min=0"));
  // INPUT programming: "The whole sequence must be received within 1 second".
  rig.sim->on_receive(ByteView(kRun2000).first(4), rig.now);
  rig.run(1100ms);
  rig.sim->on_receive(ByteView(kRun2000).subspan(4), rig.now);
  EXPECT_TRUE(rig.has("min=0"));
}

TEST(Fdc1Simulator, OutOfRangeSpeedIsIgnored) {
  SimRig rig;
  rig.run(100ms);
  rig.sim->on_receive(encode_speed({1000, 1000}), rig.now);
  EXPECT_TRUE(rig.has("rejected=1"));
  EXPECT_TRUE(rig.has("min=0"));
}

TEST(Fdc1Simulator, NormalModeRunsOnTheThermostat) {
  SimRig rig(false);
  rig.run(100ms);
  EXPECT_TRUE(rig.has("slave=0"));
  EXPECT_EQ(rig.control("thermostat on"), "ok");
  rig.run(3s);
  EXPECT_TRUE(rig.has("motor=on rpm=3000"));
}

TEST(Fdc1Simulator, InjectsAlarmsNoiseCorruptionAndSilence) {
  SimRig rig;
  rig.run(100ms);
  EXPECT_EQ(rig.control("fault temperature_eor"), "ok");
  auto s = rig.statuses(600ms);
  ASSERT_FALSE(s.empty());
  EXPECT_EQ(s.back().alarm, 208);
  EXPECT_EQ(rig.control("fault 0x21"), "ok");
  s = rig.statuses(600ms);
  EXPECT_EQ(s.back().alarm, 0x21);
  EXPECT_EQ(rig.control("clear"), "ok");
  EXPECT_TRUE(rig.has("alarm=0"));

  EXPECT_EQ(rig.control("noise 3"), "ok");
  Bytes wire = rig.run(500ms);
  EXPECT_EQ(wire.size(), 3 + kStatusSize);
  EXPECT_EQ(rig.control("corrupt 1"), "ok");
  wire = rig.run(500ms);
  ASSERT_EQ(wire.size(), kStatusSize);
  EXPECT_EQ(decode_device(wire).error, FrameError::bad_checksum);
  EXPECT_EQ(rig.control("silent on"), "ok");
  EXPECT_TRUE(rig.run(2s).empty());
  EXPECT_EQ(rig.control("silent off"), "ok");
  EXPECT_FALSE(rig.run(1s).empty());
}

// RxD cut: the controller hears nothing the master sends, and keeps streaming.
TEST(Fdc1Simulator, DeafIgnoresTheMasterButKeepsStreaming) {
  SimRig rig;
  rig.run(100ms);
  EXPECT_EQ(rig.control("deaf on"), "ok");
  EXPECT_TRUE(rig.has("deaf=1"));
  rig.sim->on_receive(kRun2000, rig.now);
  EXPECT_TRUE(rig.sim->on_receive(encode_program(Program{2000, 3000, 0, 2, {}}), rig.now).empty());
  EXPECT_FALSE(rig.statuses(1s).empty());
  EXPECT_TRUE(rig.has("min=0"));
  EXPECT_TRUE(rig.has("speeds=0"));
  EXPECT_TRUE(rig.has("programs=0"));
  EXPECT_EQ(rig.control("deaf off"), "ok");
  rig.sim->on_receive(kRun2000, rig.now);
  EXPECT_TRUE(rig.has("min=2000"));
  EXPECT_EQ(rig.control("deaf maybe").rfind("error:", 0), 0u);
}

TEST(Fdc1Simulator, HelpListsTheCommands) {
  SimRig rig;
  const std::string help = rig.control("help");
  for (const char* cmd : {"state", "fault", "clear", "silent", "deaf", "corrupt", "noise", "mangle",
                          "delay", "thermostat", "window"}) {
    EXPECT_NE(help.find(cmd), std::string::npos) << cmd;
  }
}

TEST(Fdc1Simulator, ControlAnswers) {
  SimRig rig;
  const std::string state = rig.control("state");
  for (const char* key : {"motor=", "rpm=", "alarm=", "restart_s=", "mode=", "slave=", "min=",
                          "max=", "silent=", "deaf=", "corrupt=", "speeds=", "programs="}) {
    EXPECT_NE(state.find(key), std::string::npos) << key;
  }
  const std::string unknown = rig.control("explode");
  EXPECT_EQ(unknown.rfind("error:", 0), 0u);
  EXPECT_NE(unknown.find("silent on|off"), std::string::npos);
  EXPECT_EQ(rig.control("fault nonsense").rfind("error:", 0), 0u);
  EXPECT_EQ(rig.control("silent maybe").rfind("error:", 0), 0u);
  EXPECT_EQ(rig.control("corrupt x").rfind("error:", 0), 0u);
}

}  // namespace
}  // namespace drivegate::fdc1
