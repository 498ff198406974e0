// Writes as the Modbus server makes them, on the real bus engine: the speed frame on the wire, the
// exception the PLC gets, and what `command` and `setpoint_rpm` read before and after. Speed
// frames are never acknowledged: a write is in force once the stream shows it (README, "Writes").
#include <gtest/gtest.h>

#include "bench.h"
#include "driver.h"

namespace drivegate::fdc1 {
namespace {

using Fdc1Writes = test::ReadyBench<Bench>;

TEST_F(Fdc1Writes, ASetpointWhileStoppedIsStoredThenTheRunIsInForceOnceTheMotorRuns) {
  const auto before = b.rig.sent().size();
  EXPECT_TRUE(b.stores_without_traffic(2000));
  const TimePoint asked = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});
  EXPECT_TRUE(b.not_yet_in_force(*run, "command", cmd::stop));  // until the stream shows it
  ASSERT_TRUE(b.rig.run_until([&] { return b.rig.sent().size() > before; }, 100ms));
  EXPECT_EQ(b.rig.sent().back().bytes, kRun2000);
  EXPECT_EQ(b.rig.sent().back().at, asked);  // at once: the line was free
  EXPECT_EQ(b.read("command"), cmd::stop);   // on the wire, never acknowledged: not yet
  EXPECT_EQ(b.rig.wait(run), Outcome::ok);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.read("motor_on"), 1u);  // the status that confirmed it
  EXPECT_NE(b.read("status") & kRunning, 0u);
  EXPECT_EQ(b.read("status") & kCommandPending, 0u);
  // Confirmed by the first ON frame after the run frame arrived (67 ms on the wire).
  EXPECT_LE(b.rig.now() - asked, b.on_wire(8) + kStreamPeriod);
  b.rig.run_for(2s);
  EXPECT_EQ(b.read("speed_rpm"), 2000u);
  EXPECT_EQ(b.read("sent_speed_rpm"), 2000u);
}

TEST_F(Fdc1Writes, SetpointAndRunInOneRequestRunAtThatSpeed) {
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 2500}), Outcome::ok);
  EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kRun2500});
  EXPECT_EQ(b.read("setpoint_rpm"), 2500u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_TRUE(b.sim_has("min=2500"));
}

TEST_F(Fdc1Writes, ASetpointWhileRunningIsInForceOnceTheStreamShowsTheSpeed) {
  ASSERT_TRUE(b.running_at(2000));
  const TimePoint asked = b.rig.now();
  const auto w = b.start_write({3000}, kSetpointRegister);
  EXPECT_FALSE(w->settled());
  // On the wire at once; the motor ramps at 1000 rpm/s and the setpoint in force stays 2000 rpm
  // until the stream shows it within tolerance_rpm of 3000.
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") > 2000; }, 2s));
  EXPECT_EQ(b.times_of(kRun3000), std::vector<TimePoint>{asked});
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_GE(b.read("speed_rpm"), 2900u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

TEST(Fdc1WritesFromPowerOn, StopAndQuickStopSendSpeedZero) {
  for (const std::uint16_t c : {cmd::stop, cmd::quick_stop}) {
    SCOPED_TRACE(c);
    Bench b;
    ASSERT_TRUE(b.ready());
    ASSERT_TRUE(b.running_at(2500));
    const TimePoint asked = b.rig.now();
    const auto w = b.start_write({c});
    b.rig.run_for(1ms);
    EXPECT_EQ(b.read("command"), cmd::run_forward);  // the motor still turns
    EXPECT_EQ(b.rig.wait(w), Outcome::ok);
    EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kStopFrame});  // one stop: speed 0
    EXPECT_EQ(b.read("command"), c);
    EXPECT_EQ(b.read("status") & kRunning, 0u);
    EXPECT_EQ(b.read("speed_rpm"), 0u);
    EXPECT_EQ(b.read("setpoint_rpm"), 2500u);  // kept for the next run
  }
}

TEST_F(Fdc1Writes, WritesTheControllerCannotDoChangeNothing) {
  const auto before = b.rig.sent().size();
  // One direction, and no fault reset in the protocol.
  EXPECT_EQ(b.start_write({cmd::run_reverse})->result, Outcome::invalid_value);
  EXPECT_EQ(b.start_write({cmd::reset_fault})->result, Outcome::invalid_value);
  // INPUT, Programming speed: 1500..3500 rpm.
  for (const std::uint16_t rpm : {std::uint16_t{1499}, std::uint16_t{3501}, std::uint16_t{0}}) {
    EXPECT_EQ(b.start_write({rpm}, kSetpointRegister)->result, Outcome::invalid_value) << rpm;
  }
  // No setpoint yet: nothing to run at.
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::refused);
  b.rig.run_for(1s);
  EXPECT_EQ(b.rig.sent().size(), before);
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// A PLC that starts the compressor as the gateway comes up is not told no: the run waits for the
// stream, goes out as the start-up frame, and is confirmed from the stream.
TEST(Fdc1WritesFromPowerOn, ARunBeforeTheControllerIsHeardWaitsForTheStream) {
  Bench b;
  const auto w = b.start_write({cmd::run_forward, 2000});
  EXPECT_FALSE(w->settled());
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);  // stored: nothing was running
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  EXPECT_EQ(b.frames(), std::vector<Bytes>{kRun2000});  // the start-up frame is the run
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

// ...and a controller never heard answers 0x0B once it is declared lost (stale_ms), not a
// refusal. The run it was told failed is not in force: when the controller appears hours later,
// the start-up asserts stop, not the run.
TEST(Fdc1WritesFromPowerOn, ARunToAControllerNeverHeardIsNoResponseAndNotKept) {
  Bench b;
  b.control("silent on");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 2000}), Outcome::no_response);
  EXPECT_GE(b.rig.now() - asked, 2000ms);  // stale_ms
  EXPECT_TRUE(b.rig.sent().empty());
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("status") & kRunning, 0u);
  b.rig.run_for(1h);
  b.control("silent off");
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.frames(), std::vector<Bytes>{kStopFrame});
  b.rig.run_for(3s);
  EXPECT_EQ(b.read("motor_on"), 0u);
}

TEST_F(Fdc1Writes, ANewCommandSupersedesOneNotYetSent) {
  ASSERT_EQ(b.write({2000}, kSetpointRegister), Outcome::ok);
  const TimePoint asked = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});  // from one client...
  const auto stop = b.start_write({cmd::stop});        // ...and before it reached the wire, another
  EXPECT_EQ(b.rig.wait(run), Outcome::no_response);
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kStopFrame});  // the compressor never started
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// Two clients, the same direction: one frame carries both, and both are in force with it.
TEST_F(Fdc1Writes, ASpeedChangeAndARunFromAnotherClientWaitTogether) {
  ASSERT_TRUE(b.running_at(2000));
  const TimePoint asked = b.rig.now();
  const auto faster = b.start_write({3000}, kSetpointRegister);
  const auto run = b.start_write({cmd::run_forward});
  EXPECT_EQ(b.rig.wait(run), Outcome::ok);
  EXPECT_EQ(b.rig.wait(faster), Outcome::ok);
  EXPECT_GE(b.read("speed_rpm"), 2900u);  // both confirmed at the new speed
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kRun3000});
}

// Two clients, two speeds: each goes on the line in the order asked (the gateway hands a driver
// one write at a time), each is confirmed, and the later is in force.
TEST_F(Fdc1Writes, TwoSpeedsFromTwoClientsGoOutInTheOrderAsked) {
  ASSERT_TRUE(b.running_at(2000));
  const TimePoint asked = b.rig.now();
  const auto first = b.start_write({2500}, kSetpointRegister);
  const auto second = b.start_write({3000}, kSetpointRegister);
  EXPECT_EQ(b.rig.wait(first), Outcome::ok);
  EXPECT_EQ(b.rig.wait(second), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.frames(asked), (std::vector<Bytes>{kRun2500, kRun3000}));
}

// A setpoint written while a stop is on its way is stored with the stop, once the motor is off.
TEST_F(Fdc1Writes, ASetpointWhileAStopIsOnItsWayIsStoredWithIt) {
  ASSERT_TRUE(b.running_at(2000));
  const TimePoint asked = b.rig.now();
  const auto stop = b.start_write({cmd::stop});
  const auto setpoint = b.start_write({2500}, kSetpointRegister);
  EXPECT_FALSE(setpoint->settled());
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);  // the motor still runs at 2000
  EXPECT_EQ(b.rig.wait(setpoint), Outcome::ok);
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 2500u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kStopFrame});
  // The next run uses it.
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.last(), kRun2500);
}

// A PLC writes setpoint and run_forward in one request every cycle: while running, the setpoint
// is a speed change confirmed at the new speed, and the run that follows it is held already.
TEST_F(Fdc1Writes, SetpointAndRunTogetherWhileRunningTakeOneFrame) {
  ASSERT_TRUE(b.running_at(2000));
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 2500}), Outcome::ok);
  EXPECT_NEAR(b.read("speed_rpm"), 2500, 100);  // confirmed at the new speed, not before
  EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kRun2500});
  EXPECT_EQ(b.read("setpoint_rpm"), 2500u);
  // Rewritten every 100 ms for a second, it costs the line nothing more.
  const TimePoint cyclic = b.rig.now();
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(b.write({cmd::run_forward, 2500}), Outcome::ok);
    b.rig.run_for(100ms);
  }
  EXPECT_TRUE(b.frames(cyclic).empty());
}

// --- truthful writes: what the controller did not take is not in force ---

TEST_F(Fdc1Writes, ARequestWithAnInvalidPartChangesNothing) {
  ASSERT_TRUE(b.running_at(2000));
  const TimePoint asked = b.rig.now();
  // Setpoint 3000 rpm with run_reverse: the setpoint alone would go on the line.
  EXPECT_EQ(b.start_write({cmd::run_reverse, 3000})->result, Outcome::invalid_value);
  // A valid run with a setpoint outside 1500..3500.
  EXPECT_EQ(b.start_write({cmd::run_forward, 1000})->result, Outcome::invalid_value);
  EXPECT_EQ(b.read("status") & kCommandPending, 0u);
  b.rig.run_for(1s);
  EXPECT_TRUE(b.frames(asked).empty());  // no frame at all
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_TRUE(b.sim_has("min=2000"));

  // Stopped, without a setpoint: the run is refused, and the setpoint before it in the same
  // request is not stored either.
  Bench fresh;
  ASSERT_TRUE(fresh.ready());
  const auto before = fresh.rig.sent().size();
  EXPECT_EQ(fresh.start_write({cmd::run_reverse, 2000})->result, Outcome::invalid_value);
  EXPECT_EQ(fresh.read("setpoint_rpm"), 0u);
  EXPECT_EQ(fresh.rig.sent().size(), before);
}

// The controller's receiver is cut (`deaf on`): it keeps streaming, at 2000 rpm.
TEST_F(Fdc1Writes, ASetpointWhileRunningThatTheControllerDoesNotTakeLeavesTheOldOne) {
  ASSERT_TRUE(b.running_at(2000));
  ASSERT_EQ(b.control("deaf on"), "ok");
  const TimePoint asked = b.rig.now();
  const auto w = b.start_write({3000}, kSetpointRegister);
  b.rig.run_for(4s);
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);  // never the one merely asked for
  EXPECT_EQ(b.rig.wait(w), Outcome::no_response);
  EXPECT_EQ(b.rig.now() - asked, 5000ms);  // confirm_ms, the driver's own deadline
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  // The controller is told what is in force again at once, should it have heard the 3000.
  b.rig.run_for(10ms);
  EXPECT_EQ(b.frames(asked), (std::vector<Bytes>{kRun3000, kRun2000}));
  const auto undo = b.times_of(kRun2000, asked);
  ASSERT_EQ(undo.size(), 1u);
  EXPECT_LE(undo[0] - (asked + 5000ms), 1ms);  // the engine's shortest idle wait
  // And the refresh carries 2000 rpm from then on.
  b.control("deaf off");
  b.rig.run_for(31s);
  EXPECT_EQ(b.last(), kRun2000);
  EXPECT_TRUE(b.sim_has("min=2000"));
}

TEST_F(Fdc1Writes, ASpeedChangeDuringAnAlarmIsRefusedAndTheOldOneStays) {
  ASSERT_TRUE(b.running_at(2000));
  ASSERT_EQ(b.control("fault overload"), "ok");
  ASSERT_TRUE(b.next_status());
  EXPECT_EQ(b.read("motor_on"), 0u);
  EXPECT_EQ(b.write({3000}, kSetpointRegister), Outcome::refused);
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);
  // The run stays in force: the controller retries by itself once the alarm clears.
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  b.rig.run_for(10ms);
  EXPECT_EQ(b.last(), kRun2000);  // and is what the controller is told again, at once
  b.control("clear");
  b.rig.run_for(3s);
  EXPECT_EQ(b.read("speed_rpm"), 2000u);
}

TEST_F(Fdc1Writes, ARunTheControllerRefusesIsTheExceptionAndStopStaysInForce) {
  ASSERT_EQ(b.control("fault battery"), "ok");
  ASSERT_TRUE(b.next_status());
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 2000}), Outcome::refused);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("status") & kRunning, 0u);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::supply_fault));
  // The refused run must not start the compressor when the alarm clears: stop goes out at once.
  b.rig.run_for(10ms);
  EXPECT_EQ(b.frames(asked), (std::vector<Bytes>{kRun2000, kStopFrame}));
  b.control("clear");
  b.rig.run_for(3s);
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  EXPECT_TRUE(b.sim_has("motor=off"));
}

TEST_F(Fdc1Writes, AStopTheStreamNeverShowsIsNoResponseAndTheRunStaysInForce) {
  ASSERT_TRUE(b.running_at(2000));
  ASSERT_EQ(b.control("deaf on"), "ok");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::no_response);
  EXPECT_EQ(b.read("command"), cmd::run_forward);  // what the controller does, and is told again
  EXPECT_NE(b.read("status") & kRunning, 0u);
  b.rig.run_for(10ms);
  EXPECT_EQ(b.frames(asked), (std::vector<Bytes>{kStopFrame, kRun2000}));
  EXPECT_EQ(b.read("speed_rpm"), 2000u);
}

TEST_F(Fdc1Writes, ARunNotShownWithinConfirmMsIsNoResponseAndIsUndone) {
  ASSERT_EQ(b.control("delay 10"), "ok");  // 10 s until the next start, no alarm
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 2000}), Outcome::no_response);
  EXPECT_EQ(b.rig.now() - asked, 5000ms);
  EXPECT_EQ(b.read("command"), cmd::stop);
  b.rig.run_for(10ms);
  EXPECT_EQ(b.frames(asked), (std::vector<Bytes>{kRun2000, kStopFrame}));
  // When the restart delay ends, the compressor the PLC was told did not start stays off.
  b.rig.run_for(10s);
  EXPECT_TRUE(b.sim_has("motor=off"));
  EXPECT_EQ(b.read("speed_rpm"), 0u);
}

// The controller goes silent with a speed change on the wire: it takes the new speed unheard,
// the PLC gets 0x0B, and when the stream returns the start-up puts it back on what is in force.
TEST_F(Fdc1Writes, CommLostFailsTheWriteAndTheStartUpRestoresWhatIsInForce) {
  ASSERT_TRUE(b.running_at(2000));
  b.control("silent on");
  EXPECT_EQ(b.write({2500}, kSetpointRegister), Outcome::no_response);
  EXPECT_NE(b.read("status") & kCommLost, 0u);
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_TRUE(b.sim_has("min=2500"));  // it did take it, unheard
  b.control("silent off");
  const TimePoint back = b.rig.now();
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.frames(back), std::vector<Bytes>{kRun2000});
  b.rig.run_for(2s);
  EXPECT_EQ(b.read("speed_rpm"), 2000u);
  EXPECT_TRUE(b.sim_has("min=2000"));
}

}  // namespace
}  // namespace drivegate::fdc1
