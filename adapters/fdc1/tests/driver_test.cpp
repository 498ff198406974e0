// The driver against its simulator on the real bus engine: the start-up, the refresh that keeps
// the 60 s watchdog from stopping the motor, the stream into the registers a PLC reads, alarms,
// noise, comm_lost and recovery, asserted on the frames on the wire (with their simulated times
// where timing matters) and on the registers.
#include "driver.h"

#include <gtest/gtest.h>

#include "bench.h"
#include "points.h"

namespace drivegate::fdc1 {
namespace {

TEST(Fdc1DriverFromPowerOn, TraitsFollowTheOptions) {
  Bench b({.options = {{"slave_mode", "true"}, {"stale_ms", "3000"}, {"confirm_ms", "8000"}}});
  const DriverTraits t = b.drive->driver().traits();
  EXPECT_EQ(t.comm_timeout, 3000ms);
  EXPECT_EQ(t.write_timeout, 9000ms);  // outlasts confirm_ms: the driver answers first
  EXPECT_EQ(t.inter_frame_gap, 0ms);   // separate RxD / TxD
  EXPECT_EQ(b.drive->driver().points().size(), pt::prog_min_rpm);  // no programming points
  EXPECT_EQ(b.drive->map().find("prog_commit"), nullptr);
}

TEST(Fdc1DriverFromPowerOn, StartUpWaitsForTheStreamThenAssertsStopAtOnce) {
  Bench b;
  EXPECT_EQ(b.read("status") & kOnline, 0u);
  ASSERT_TRUE(b.ready());
  // Nothing before the controller is heard; then the stop in force (INPUT speed, SLAVE MODE:
  // minimum 0 stops) as soon as the first status has arrived (8 bytes on the wire).
  ASSERT_EQ(b.rig.sent().size(), 1u);
  EXPECT_EQ(b.rig.sent()[0].bytes, kStopFrame);
  ASSERT_FALSE(b.rig.answers().empty());
  const TimePoint first_status = b.rig.answers()[0].at + b.on_wire(kStatusSize);
  EXPECT_GE(b.rig.sent()[0].at, first_status);
  EXPECT_LE(b.rig.sent()[0].at - first_status, 1ms);  // the engine's shortest idle wait
  EXPECT_EQ(b.read("status") & (kOnline | kRunning | kFaulted), kOnline);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
  EXPECT_EQ(b.read("motor_on"), 0u);
  EXPECT_EQ(b.read("sent_speed_rpm"), 0u);
  EXPECT_TRUE(b.sim_has("min=0"));
}

// A compressor found turning on an earlier session's speed frames (the gateway
// restarted, or this device was changed by a reload) is kept turning at the speed it reports and
// shown so: the first frame is a run at that speed, never the stop above.
TEST(Fdc1DriverFromPowerOn, ACompressorFoundTurningIsKeptTurningNeverStopped) {
  Bench b;
  ASSERT_EQ(b.control("run 2500"), "ok");
  ASSERT_TRUE(b.ready());
  ASSERT_EQ(b.rig.sent().size(), 1u);
  EXPECT_EQ(b.rig.sent()[0].bytes, kRun2500);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.read("setpoint_rpm"), 2500u);
  EXPECT_NE(b.read("status") & kRunning, 0u);
  b.rig.run_for(3s);
  EXPECT_EQ(b.read("speed_rpm"), 2500u);
  EXPECT_TRUE(b.sim_has("motor=on"));
  // And a stop from the PLC stops it as any other run.
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_TRUE(b.sim_has("motor=off"));
}

using Fdc1Driver = test::ReadyBench<Bench>;

// After a comm_lost the gateway's own order stands: what it last told the controller.
TEST_F(Fdc1Driver, AfterCommLostAStoppedOrderIsNotAdopted) {
  b.control("silent on");
  ASSERT_TRUE(b.rig.run_until([&] { return (b.read("status") & kCommLost) != 0; }, 3s));
  ASSERT_EQ(b.control("run 3000"), "ok");  // someone else ran it meanwhile
  b.control("silent off");
  const TimePoint back = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 2s));
  b.rig.run_for(100ms);
  EXPECT_EQ(b.frames(back), std::vector<Bytes>{kStopFrame});
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST(Fdc1DriverFromPowerOn, OutsideSlaveModeTheLineOnlyMonitors) {
  Bench b({.options = {}});
  ASSERT_TRUE(b.ready());
  b.rig.run_for(5s);
  EXPECT_TRUE(b.rig.sent().empty());
  EXPECT_NE(b.read("status") & kOnline, 0u);
  // IN1 / IN2 and the thermostat set the speed: the line cannot run, stop or set it (0x03).
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::invalid_value);
  EXPECT_EQ(b.write({cmd::stop}), Outcome::invalid_value);
  EXPECT_EQ(b.write({2000}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_TRUE(b.rig.sent().empty());
  // What the controller does on its own is still monitored.
  EXPECT_EQ(b.control("thermostat on"), "ok");
  b.rig.run_for(3s);
  EXPECT_EQ(b.read("speed_rpm"), 3000u);  // normal mode runs at the programmed maximum
  EXPECT_NE(b.read("status") & kRunning, 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);  // the gateway commanded nothing
}

TEST_F(Fdc1Driver, TheRefreshKeepsTheMotorRunningPastTheWatchdog) {
  ASSERT_TRUE(b.running_at(2000));
  const auto runs = b.times_of(kRun2000);
  ASSERT_EQ(runs.size(), 1u);
  b.rig.run_for(181s);  // three watchdog windows
  const auto refreshes = b.times_of(kRun2000);
  ASSERT_EQ(refreshes.size(), 7u);  // refresh_s = 30
  for (std::size_t i = 1; i < refreshes.size(); ++i) {
    EXPECT_EQ(refreshes[i] - refreshes[i - 1], 30s);
  }
  EXPECT_EQ(b.frames().size(), 8u);  // the start-up stop, then only the run
  EXPECT_EQ(b.read("speed_rpm"), 2000u);
  EXPECT_TRUE(b.sim_has("motor=on"));
  EXPECT_TRUE(b.sim_has("watchdog=0"));
}

TEST(Fdc1DriverFromPowerOn, ARefreshEveryFewSecondsOutlastsAShortenedWindow) {
  Bench b({.options = {{"slave_mode", "true"}, {"refresh_s", "2"}}});
  ASSERT_EQ(b.control("window 5"), "ok");
  ASSERT_TRUE(b.ready());
  ASSERT_TRUE(b.running_at(2000));
  b.rig.run_for(20s);
  EXPECT_TRUE(b.sim_has("motor=on"));
  const auto refreshes = b.times_of(kRun2000);
  ASSERT_GE(refreshes.size(), 10u);
  EXPECT_EQ(refreshes.back() - refreshes[refreshes.size() - 2], 2s);
}

TEST_F(Fdc1Driver, TheStreamAsAPlcReadsIt) {
  ASSERT_TRUE(b.running_at(2000));
  EXPECT_EQ(b.read("motor_on"), 1u);
  EXPECT_EQ(b.read("current_a"), 2400u);  // 2000 rpm x 0.0012 A/rpm, in mA
  EXPECT_EQ(b.read("restart_s"), 0u);
  EXPECT_EQ(b.read("sent_speed_rpm"), 2000u);
  EXPECT_EQ(b.read("alarm_code"), 0u);
  EXPECT_NE(b.read("status") & kRunning, 0u);
  ASSERT_EQ(b.write({cmd::stop}), Outcome::ok);
  ASSERT_EQ(b.control("delay 100"), "ok");  // 100 s until the next start, no alarm
  b.rig.run_for(1s);
  EXPECT_EQ(b.read("motor_on"), 0u);
  EXPECT_EQ(b.read("current_a"), 0u);
  EXPECT_NEAR(b.read("restart_s"), 990.0, 6.0);  // 0.1 s registers, one stream period late
  EXPECT_EQ(b.read("sent_speed_rpm"), 0u);
}

TEST_F(Fdc1Driver, AlarmsBecomeUnifiedFaultsWithTheRawCode) {
  const auto show = [&](const char* command) {
    EXPECT_EQ(b.control(command), "ok");
    b.rig.run_for(1s);
  };
  show("fault start");
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::stall));
  EXPECT_EQ(b.read("native_fault"), 48u);
  EXPECT_EQ(b.read("alarm_code"), 48u);
  EXPECT_EQ(b.read("alarm_latched"), 0u);
  EXPECT_NE(b.read("status") & kFaulted, 0u);
  show("fault overload_eor");
  EXPECT_EQ(b.read("fault_mask"), 1u << static_cast<unsigned>(Fault::overload));
  EXPECT_EQ(b.read("native_fault"), 192u);
  EXPECT_EQ(b.read("alarm_latched"), 1u);
  show("fault 0xF3");
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::internal_error));
  EXPECT_EQ(b.read("native_fault"), 0xF3u);
  show("fault 100");  // in no range of the document
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::other));
  show("clear");
  EXPECT_EQ(b.read("fault_mask"), 0u);
  EXPECT_EQ(b.read("native_fault"), 0u);
  EXPECT_EQ(b.read("status") & kFaulted, 0u);
}

// The run in force is re-asserted when the stream comes back (docs/safety.md counts on it): the
// controller may have stopped on its own watchdog meanwhile.
TEST_F(Fdc1Driver, CommLostThenTheStartUpSendsTheOrderInForceAgain) {
  ASSERT_TRUE(b.running_at(2000));
  b.control("silent on");
  const TimePoint silent = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return (b.read("status") & kCommLost) != 0; }, 3s));
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::comm_lost));
  EXPECT_EQ(b.read("status") & kOnline, 0u);
  b.rig.run_for(60s);
  EXPECT_TRUE(b.frames(silent).empty());  // nothing is sent to a controller not heard
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);
  b.control("silent off");
  const TimePoint back = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 2s));
  b.rig.run_for(100ms);
  ASSERT_EQ(b.frames(back), std::vector<Bytes>{kRun2000});
  b.rig.run_for(3s);
  EXPECT_EQ(b.read("speed_rpm"), 2000u);
}

TEST_F(Fdc1Driver, NoiseAndBadChecksumsInTheStreamCostFramesNotTheLink) {
  b.control("noise 7");
  b.rig.run_for(500ms);
  b.control("corrupt 2");
  b.rig.run_for(1500ms);
  EXPECT_EQ(b.read("bad_checksum"), 2u);
  EXPECT_GT(b.drive->line().counters.noise_bytes, 0u);  // skipped up to the next header
  EXPECT_EQ(b.read("status") & kCommLost, 0u);
  const std::uint32_t good = b.read("frames_good");
  b.rig.run_for(1s);
  EXPECT_EQ(b.read("frames_good"), good + 2);  // OUTPUT: every 0.5 s
  EXPECT_LT(b.read("data_age_ms"), 600u);
}

}  // namespace
}  // namespace drivegate::fdc1
