// The driver against the simulator on simulated time: the exact speed frames on the wire, when
// they go, how writes complete from the stream, alarms, and comm_lost recovery.
#include "driver.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "fixture.h"
#include "points.h"

namespace drivegate::fdc1 {
namespace {

using namespace test_support;
using namespace std::chrono_literals;

std::int64_t int_of(const Value& v) {
  return std::get<std::int64_t>(v);
}

TEST(Fdc1Driver, TraitsFollowTheOptions) {
  Rig rig;
  EXPECT_EQ(rig.driver->traits().comm_timeout, 2000ms);
  EXPECT_GT(rig.driver->traits().write_timeout, 5000ms);  // outlasts confirm_ms
  EXPECT_EQ(rig.driver->points().size(), pt::status_count);
}

TEST(Fdc1Driver, StartUpWaitsForTheStreamThenAssertsStop) {
  Rig rig;
  EXPECT_FALSE(rig.driver->next_exchange(rig.now()));  // nothing before the device is heard
  EXPECT_FALSE(rig.common().ready);
  rig.bus->run_for(600ms);
  EXPECT_TRUE(rig.common().ready);
  ASSERT_EQ(rig.bus->sent.size(), 1u);
  EXPECT_EQ(rig.bus->sent[0], kStopFrame);  // INPUT speed, SLAVE MODE: minimum 0 stops
  EXPECT_EQ(rig.common().command, Command::stop);
  EXPECT_GE(rig.bus->good_frames, 2);
}

TEST(Fdc1Driver, OutsideSlaveModeTheLineOnlyMonitors) {
  auto options = slave_options();
  options["slave_mode"] = false;
  Rig rig(options);
  rig.bus->run_for(5s);
  EXPECT_TRUE(rig.bus->sent.empty());
  EXPECT_TRUE(rig.common().ready);
  EXPECT_EQ(rig.driver->command(Command::run_forward, 1, rig.now()), WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->command(Command::stop, 2, rig.now()), WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->setpoint(2000, 3, rig.now()), WriteStatus::invalid_value);
}

TEST(Fdc1Driver, RunsAt2000AndConfirmsFromTheStream) {
  Rig rig;
  rig.bus->run_for(600ms);
  EXPECT_EQ(rig.driver->setpoint(2000, 1, rig.now()), WriteStatus::done);  // stored while stopped
  EXPECT_EQ(rig.common().setpoint_rpm, 2000);
  EXPECT_EQ(rig.bus->sent.size(), 1u);  // no traffic for a stored setpoint
  EXPECT_EQ(rig.driver->command(Command::run_forward, 2, rig.now()), WriteStatus::pending);
  EXPECT_EQ(rig.driver->next_exchange(rig.now())->priority, Priority::command);
  rig.bus->sent.push_back(kRun2000);  // what the line just carried (we took it above)
  rig.sim->on_receive(kRun2000, rig.now());
  ASSERT_TRUE(rig.settle(2));
  EXPECT_EQ(rig.result(2), WriteResult::ok);
  EXPECT_EQ(rig.bus->sent, (std::vector<Bytes>{kStopFrame, kRun2000}));
  rig.bus->run_for(2s);
  EXPECT_TRUE(rig.common().running);
  EXPECT_EQ(rig.common().speed_rpm, 2000);
  EXPECT_EQ(rig.common().command, Command::run_forward);
  EXPECT_EQ(int_of(rig.value(pt::motor_on)), 1);
  EXPECT_NEAR(std::get<double>(rig.value(pt::current_a)), 2.4, 0.001);
  EXPECT_EQ(int_of(rig.value(pt::sent_speed_rpm)), 2000);
}

TEST(Fdc1Driver, RefreshKeepsTheMotorRunningPastTheWatchdog) {
  Rig rig;
  rig.bus->run_for(600ms);
  ASSERT_EQ(rig.driver->setpoint(2000, 1, rig.now()), WriteStatus::done);
  ASSERT_EQ(rig.driver->command(Command::run_forward, 2, rig.now()), WriteStatus::pending);
  rig.bus->run_for(29s);
  EXPECT_EQ(rig.bus->sent.size(), 2u);  // stop at start-up, run; no refresh yet
  rig.bus->run_for(2s);
  EXPECT_EQ(rig.bus->sent.size(), 3u);  // refresh_s = 30
  rig.bus->run_for(150s);
  EXPECT_EQ(rig.bus->sent.size(), 8u);
  for (std::size_t i = 1; i < rig.bus->sent.size(); ++i) EXPECT_EQ(rig.bus->sent[i], kRun2000);
  EXPECT_EQ(rig.common().speed_rpm, 2000);
  EXPECT_NE(rig.state().find("motor=on"), std::string::npos);
  EXPECT_NE(rig.state().find("watchdog=0"), std::string::npos);
  EXPECT_EQ(rig.result(2), WriteResult::ok);
}

TEST(Fdc1Driver, SetpointWhileRunningIsSentAndConfirmedAtSpeed) {
  Rig rig;
  ASSERT_TRUE(rig.run_at(2000));
  rig.bus->run_for(1s);
  EXPECT_EQ(rig.driver->setpoint(3000, 3, rig.now()), WriteStatus::pending);
  ASSERT_TRUE(rig.settle(3));
  EXPECT_EQ(rig.result(3), WriteResult::ok);
  EXPECT_EQ(rig.bus->sent.back(), kRun3000);
  EXPECT_GE(rig.common().speed_rpm, 2900);  // confirmed within tolerance_rpm of 3000
  EXPECT_EQ(rig.common().setpoint_rpm, 3000);
}

TEST(Fdc1Driver, StopAndQuickStopSendSpeedZero) {
  for (const Command c : {Command::stop, Command::quick_stop}) {
    SCOPED_TRACE(to_string(c));
    Rig rig;
    ASSERT_TRUE(rig.run_at(2500));
    EXPECT_EQ(rig.driver->command(c, 3, rig.now()), WriteStatus::pending);
    ASSERT_TRUE(rig.settle(3));
    EXPECT_EQ(rig.result(3), WriteResult::ok);
    EXPECT_EQ(rig.bus->sent.back(), kStopFrame);
    EXPECT_FALSE(rig.common().running);
    EXPECT_EQ(rig.common().speed_rpm, 0);
    EXPECT_EQ(rig.common().command, c);
  }
}

TEST(Fdc1Driver, WritesTheControllerCannotDo) {
  Rig rig;
  rig.bus->run_for(600ms);
  EXPECT_EQ(rig.driver->command(Command::run_reverse, 1, rig.now()), WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->command(Command::reset_fault, 2, rig.now()), WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->setpoint(1499, 3, rig.now()), WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->setpoint(3501, 4, rig.now()), WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->setpoint(0, 5, rig.now()), WriteStatus::invalid_value);
  // No setpoint yet: nothing to run at.
  EXPECT_EQ(rig.driver->command(Command::run_forward, 6, rig.now()), WriteStatus::refused);
  EXPECT_EQ(rig.bus->sent.size(), 1u);
}

// A PLC that starts the compressor as the gateway comes up is not told no: the run waits for
// the stream, goes out as the start-up frame, and is confirmed from the stream.
TEST(Fdc1Driver, ARunBeforeTheDeviceIsHeardWaitsForTheStream) {
  Rig rig;
  EXPECT_EQ(rig.driver->setpoint(2000, 1, rig.now()), WriteStatus::done);
  EXPECT_EQ(rig.driver->command(Command::run_forward, 2, rig.now()), WriteStatus::pending);
  EXPECT_FALSE(rig.driver->next_exchange(rig.now()));  // nothing until the controller is heard
  ASSERT_TRUE(rig.settle(2));
  EXPECT_EQ(rig.result(2), WriteResult::ok);
  EXPECT_EQ(rig.bus->sent, (std::vector<Bytes>{kRun2000}));  // the start-up frame is the run
  EXPECT_EQ(rig.common().command, Command::run_forward);
}

// ...and a controller never heard answers 0x0B once it is declared lost (stale_ms, 2000), not
// a refusal. The run it was told failed does not stay in force: when the controller appears
// later, the start-up asserts stop, not the run.
TEST(Fdc1Driver, ARunToAControllerNeverHeardIsNoResponseAndNotKept) {
  Rig rig;
  rig.sim->control("silent on", rig.now());
  ASSERT_EQ(rig.driver->setpoint(2000, 1, rig.now()), WriteStatus::done);
  EXPECT_EQ(rig.driver->command(Command::run_forward, 2, rig.now()), WriteStatus::pending);
  rig.bus->run_for(1900ms);
  EXPECT_FALSE(rig.completed(2));
  ASSERT_TRUE(rig.settle(2, 200ms));
  EXPECT_EQ(rig.result(2), WriteResult::no_response);
  EXPECT_TRUE(rig.bus->sent.empty());
  EXPECT_EQ(rig.common().command, Command::stop);
  EXPECT_FALSE(rig.common().running);

  rig.bus->run_for(1h);  // hours later the controller is powered up
  rig.sim->control("silent off", rig.now());
  rig.bus->run_for(2s);
  ASSERT_TRUE(rig.common().ready);
  ASSERT_EQ(rig.bus->sent.size(), 1u);
  EXPECT_EQ(rig.bus->sent[0], kStopFrame);
  EXPECT_EQ(int_of(rig.value(pt::motor_on)), 0);
}

// A setpoint change while running that no frame ever carried goes back too.
TEST(Fdc1Driver, ASpeedChangeNeverSentGoesBackWithTheLink) {
  Rig rig;
  ASSERT_TRUE(rig.run_at(2000));
  rig.sim->control("silent on", rig.now());
  rig.bus->run_for(2500ms);  // comm_lost: not ready
  EXPECT_FALSE(rig.common().ready);
  // The device layer answers 0x0B itself while comm_lost; the driver on its own still copes.
  EXPECT_EQ(rig.driver->setpoint(3000, 3, rig.now()), WriteStatus::pending);
  rig.driver->on_comm_lost(rig.now());
  ASSERT_TRUE(rig.settle(3, 100ms));
  EXPECT_EQ(rig.result(3), WriteResult::no_response);
  EXPECT_EQ(rig.common().setpoint_rpm, 2000);
  EXPECT_EQ(rig.common().command, Command::run_forward);  // the confirmed run stays in force
}

TEST(Fdc1Driver, AlarmsBecomeUnifiedFaultsWithTheRawCode) {
  Rig rig;
  rig.bus->run_for(600ms);
  rig.sim->control("fault start", rig.now());
  rig.bus->run_for(1s);
  EXPECT_TRUE(rig.common().faults.has(Fault::stall));
  EXPECT_EQ(rig.common().native_fault, 48u);
  EXPECT_EQ(int_of(rig.value(pt::alarm_code)), 48);
  EXPECT_EQ(int_of(rig.value(pt::alarm_latched)), 0);
  rig.sim->control("fault overload_eor", rig.now());
  rig.bus->run_for(1s);
  FaultSet overload;
  overload.set(Fault::overload);
  EXPECT_EQ(rig.common().faults, overload);
  EXPECT_EQ(rig.common().native_fault, 192u);
  EXPECT_EQ(int_of(rig.value(pt::alarm_latched)), 1);
  rig.sim->control("fault 0xF3", rig.now());
  rig.bus->run_for(1s);
  EXPECT_TRUE(rig.common().faults.has(Fault::internal_error));
  EXPECT_EQ(rig.common().native_fault, 0xF3u);
  rig.sim->control("clear", rig.now());
  rig.bus->run_for(1s);
  EXPECT_TRUE(rig.common().faults.empty());
  EXPECT_EQ(rig.common().native_fault, 0u);
}

TEST(Fdc1Driver, RunDuringAnAlarmIsRefusedByTheStream) {
  Rig rig;
  rig.bus->run_for(600ms);
  rig.sim->control("fault battery", rig.now());
  rig.bus->run_for(1s);
  rig.driver->setpoint(2000, 1, rig.now());
  ASSERT_EQ(rig.driver->command(Command::run_forward, 2, rig.now()), WriteStatus::pending);
  ASSERT_TRUE(rig.settle(2));
  EXPECT_EQ(rig.result(2), WriteResult::refused);
  EXPECT_TRUE(rig.common().faults.has(Fault::supply_fault));
  // A refused run does not stay in force: stop goes out, so the controller does not start by
  // itself when the alarm clears after the PLC was told no.
  EXPECT_EQ(rig.common().command, Command::stop);
  rig.bus->run_for(100ms);
  EXPECT_EQ(rig.bus->sent.back(), kStopFrame);
  rig.sim->control("clear", rig.now());
  rig.bus->run_for(3s);
  EXPECT_EQ(rig.common().speed_rpm, 0);
  EXPECT_FALSE(rig.common().running);
}

TEST(Fdc1Driver, UnconfirmedWriteFailsAfterConfirmMs) {
  Rig rig;
  rig.bus->run_for(600ms);
  rig.sim->control("delay 100", rig.now());  // 100 s until the next start, no alarm
  rig.bus->run_for(1s);
  EXPECT_NEAR(std::get<double>(rig.value(pt::restart_s)), 99.0, 0.6);
  rig.driver->setpoint(2000, 1, rig.now());
  const TimePoint asked = rig.now();
  ASSERT_EQ(rig.driver->command(Command::run_forward, 2, rig.now()), WriteStatus::pending);
  ASSERT_TRUE(rig.settle(2));
  EXPECT_EQ(rig.result(2), WriteResult::no_response);
  EXPECT_GE(rig.now() - asked, 5000ms);
  EXPECT_LT(rig.now() - asked, 5100ms);
}

TEST(Fdc1Driver, ANewSpeedWriteSupersedesThePendingOne) {
  Rig rig;
  rig.bus->run_for(600ms);
  rig.driver->setpoint(2000, 1, rig.now());
  ASSERT_EQ(rig.driver->command(Command::run_forward, 2, rig.now()), WriteStatus::pending);
  ASSERT_EQ(rig.driver->command(Command::stop, 3, rig.now()), WriteStatus::pending);
  rig.bus->run_for(1s);
  EXPECT_EQ(rig.result(2), WriteResult::no_response);
  EXPECT_EQ(rig.result(3), WriteResult::ok);
  EXPECT_EQ(rig.bus->sent.back(), kStopFrame);
  EXPECT_EQ(rig.bus->sent.size(), 2u);  // only the latest state goes out
}

// A PLC writes setpoint and run_forward in one request every cycle: while running, the setpoint
// is a pending speed change and the run a second speed write for the same frame. Both complete
// ok when the stream shows the new speed, not 0x0B for the first.
TEST(Fdc1Driver, SetpointAndRunTogetherWhileRunningBothComplete) {
  Rig rig;
  ASSERT_TRUE(rig.run_at(2000));
  ASSERT_EQ(rig.result(2), WriteResult::ok);
  rig.bus->run_for(1s);
  ASSERT_EQ(rig.driver->setpoint(2500, 3, rig.now()), WriteStatus::pending);
  ASSERT_EQ(rig.driver->command(Command::run_forward, 4, rig.now()), WriteStatus::pending);
  ASSERT_TRUE(rig.settle(4));
  ASSERT_TRUE(rig.settle(3));
  EXPECT_EQ(rig.result(3), WriteResult::ok);
  EXPECT_EQ(rig.result(4), WriteResult::ok);
  EXPECT_NEAR(rig.common().speed_rpm, 2500, 100);  // confirmed at the new speed, not before
  EXPECT_EQ(rig.bus->sent.back(), (Bytes{0x48, 0x73, 0x09, 0xC4, 0x09, 0xC4, 0x55, 0x6E}));
}

TEST(Fdc1Driver, CommLostFailsPendingWritesAndStartUpRunsAgain) {
  Rig rig;
  ASSERT_TRUE(rig.run_at(2000));
  rig.sim->control("silent on", rig.now());
  ASSERT_EQ(rig.driver->setpoint(2500, 3, rig.now()), WriteStatus::pending);
  ASSERT_TRUE(rig.bus->run_until([&] { return rig.bus->comm_lost(); }, 3s));
  rig.bus->run_for(10ms);
  EXPECT_EQ(rig.result(3), WriteResult::no_response);
  EXPECT_FALSE(rig.common().ready);
  const auto sent_before = rig.bus->sent.size();
  rig.bus->run_for(5s);
  EXPECT_EQ(rig.bus->sent.size(), sent_before);  // nothing is sent to a silent controller
  rig.sim->control("silent off", rig.now());
  rig.bus->run_for(600ms);
  EXPECT_TRUE(rig.common().ready);
  ASSERT_EQ(rig.bus->sent.size(), sent_before + 1);
  // The command in force (run, at the last setpoint) is asserted again at once.
  EXPECT_EQ(rig.bus->sent.back(), (Bytes{0x48, 0x73, 0x09, 0xC4, 0x09, 0xC4, 0x55, 0x6E}));
}

TEST(Fdc1Driver, NoiseAndBadChecksumsInTheStreamAreSurvived) {
  Rig rig;
  rig.bus->run_for(600ms);
  rig.sim->control("noise 7", rig.now());
  rig.bus->run_for(500ms);
  rig.sim->control("corrupt 2", rig.now());
  rig.bus->run_for(1500ms);
  EXPECT_EQ(rig.bus->bad_frames, 2);
  EXPECT_FALSE(rig.bus->comm_lost());
  EXPECT_TRUE(rig.common().ready);
  const int good = rig.bus->good_frames;
  rig.bus->run_for(1s);
  EXPECT_EQ(rig.bus->good_frames, good + 2);
}

TEST(Fdc1Driver, EveryNonIncompleteVerdictConsumes) {
  Rig rig;
  Bytes junk;
  for (int i = 0; i < 300; ++i) junk.push_back(static_cast<std::uint8_t>((i * 37 + 11) % 256));
  junk.insert(junk.end(), {0x1B, 0x4C, 0x1B, 0x50, 0x1B});
  std::size_t at = 0;
  while (at < junk.size()) {
    const RxVerdict v = rig.driver->on_receive(ByteView(junk).subspan(at), rig.now());
    if (v.kind == RxKind::incomplete) break;
    ASSERT_GT(v.consumed, 0u);
    at += v.consumed;
  }
}

TEST(Fdc1Driver, WakesForTheRefreshAndTheConfirmDeadline) {
  Rig rig;
  EXPECT_EQ(rig.driver->wake_at(), TimePoint::max());
  rig.bus->run_for(600ms);
  const TimePoint refresh = rig.driver->wake_at();
  EXPECT_GT(refresh, rig.now() + 29s);
  EXPECT_LE(refresh, rig.now() + 30s);
  rig.driver->setpoint(2000, 1, rig.now());
  rig.driver->command(Command::run_forward, 2, rig.now());
  EXPECT_LE(rig.driver->wake_at(), rig.now());  // the run frame is due at once
  ASSERT_TRUE(rig.driver->next_exchange(rig.now()));
  EXPECT_GT(rig.driver->wake_at(), rig.now());
  EXPECT_LE(rig.driver->wake_at(), rig.now() + 5s);  // the confirm deadline
}

}  // namespace
}  // namespace drivegate::fdc1
