// Writes as the Modbus server makes them, on the real bus engine: what goes on the wire, the
// exception the PLC gets, and what `command` and `setpoint_rpm` read afterwards. A write is in
// force once the run reply echoed the code that carried it (README, "Commands and writes").
#include <gtest/gtest.h>

#include "bench.h"
#include "driver.h"

namespace drivegate::mdriver {
namespace {

using MdriverWrites = test::ReadyBench<Bench>;

TEST_F(MdriverWrites, ASetpointWhileStoppedIsStoredThenRunGoesOutAsCode40) {
  EXPECT_TRUE(b.runs_from_stopped(1149, kRun1149, kInterFrameGap));  // in force once echoed
  b.rig.run_for(4s);  // 0x1C..0x40 at 20 codes a second
  EXPECT_EQ(b.read("speed_rpm"), 1149u);
  EXPECT_EQ(b.read("actual_code"), 0x40u);
  EXPECT_EQ(b.read("target_code"), 0x40u);
  EXPECT_EQ(b.read("target_rpm"), 1149u);
  EXPECT_EQ(b.read("sent_code"), 0x40u);
  EXPECT_EQ(b.last(), kRun1149);  // the keep-alive carries the target in force
}

TEST(MdriverWritesFromPowerOn, ContinuousModeSendsFF) {
  Bench b({.options = {{"mode", "continuous"}}});
  ASSERT_TRUE(b.ready());
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 1149}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kRun1149Continuous);
}

TEST_F(MdriverWrites, ASetpointWhileRunningIsInForceOnceTheDriveEchoedIt) {
  ASSERT_TRUE(b.running_at_1149());
  const auto w = b.start_write({504}, kSetpointRegister);
  EXPECT_FALSE(w->settled());
  ASSERT_TRUE(b.rig.run_until([&] { return b.last() == kRun504; }, 100ms));
  // On the wire, not answered yet: the drive holds 1149 rpm still.
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 504u);
  EXPECT_EQ(b.read("target_code"), 0x1Cu);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  b.rig.run_for(1s);
  EXPECT_EQ(b.last(), kRun504);
}

TEST_F(MdriverWrites, SetpointRangeAndNearestEntry) {
  // Section 3 No.2: nothing under 504 rpm; the table ends at 2856 rpm.
  EXPECT_EQ(b.write({503}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(b.write({0}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(b.write({2857}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(b.write({static_cast<std::uint16_t>(-600)}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);  // none of them stored
  EXPECT_EQ(b.write({2856}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 2856u);
  EXPECT_EQ(b.write({1160}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 1167u);  // the nearest entry, 0x41
}

TEST_F(MdriverWrites, StopQuickStopAndReverse) {
  ASSERT_TRUE(b.running_at_1149());
  const auto before = b.rig.sent().size();
  EXPECT_EQ(b.start_write({cmd::run_reverse})->result,
            Outcome::invalid_value);  // one direction
  EXPECT_EQ(b.rig.sent().size(), before);
  TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::quick_stop}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kRunStop);  // the protocol has one stop
  EXPECT_EQ(b.read("command"), cmd::stop);
  asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kRunStop);
  b.rig.run_for(3s);
  EXPECT_EQ(b.last(), kRunStop);
  EXPECT_EQ(b.read("status") & kRunning, 0u);
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  EXPECT_EQ(b.count(kRunReset), 0u);  // a plain stop never resets errors
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
}

TEST(MdriverWritesFromPowerOn, CommandsAreRefusedBeforeTheCheckAndARunWithoutSetpoint) {
  Bench b;
  EXPECT_EQ(b.start_write({cmd::stop})->result, Outcome::refused);
  EXPECT_EQ(b.start_write({1149}, kSetpointRegister)->result, Outcome::ok);  // stored
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
  EXPECT_TRUE(b.rig.sent().empty());

  Bench fresh;
  ASSERT_TRUE(fresh.ready());
  const auto before = fresh.rig.sent().size();
  EXPECT_EQ(fresh.start_write({cmd::run_forward})->result, Outcome::refused);
  EXPECT_EQ(fresh.rig.sent().size(), before);
  EXPECT_EQ(fresh.read("command"), cmd::stop);
}

TEST_F(MdriverWrites, ACommandWrittenOverAnotherNotYetSentSupersedesIt) {
  ASSERT_EQ(b.write({1149}, kSetpointRegister), Outcome::ok);
  const TimePoint asked = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});  // from one client...
  const auto stop = b.start_write({cmd::stop});        // ...and before it reached the wire, another
  EXPECT_EQ(run->result, Outcome::no_response);
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.frames(asked), std::vector<Bytes>{kRunStop});  // the compressor never started
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// --- truthful writes: what the drive did not take is not in force ---

TEST_F(MdriverWrites, ARequestWithAnInvalidPartChangesNothing) {
  ASSERT_TRUE(b.running_at_1149());
  // Setpoint 600 rpm (code 0x21) with run_reverse: the setpoint alone would go on the line.
  const auto before = b.rig.sent().size();
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.start_write({cmd::run_reverse, 600})->result, Outcome::invalid_value);
  EXPECT_EQ(b.rig.sent().size(), before);
  b.rig.run_for(1s);
  for (const auto& f : b.frames(asked)) EXPECT_EQ(f, kRun1149);  // keep-alives only
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);

  // Tripped: run_forward is refused, so the setpoint in the same request is not sent either.
  b.control("fault stall");
  b.rig.run_for(600ms);
  ASSERT_NE(b.read("status") & kFaulted, 0u);
  const TimePoint tripped = b.rig.now();
  EXPECT_EQ(b.start_write({cmd::run_forward, 600})->result, Outcome::refused);
  b.rig.run_for(1s);
  for (const auto& f : b.frames(tripped)) EXPECT_EQ(f, kRun1149);
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
}

TEST_F(MdriverWrites, ASetpointTheDriveDoesNotAnswerLeavesTheOldOneInForce) {
  ASSERT_TRUE(b.running_at_1149());
  b.control("silent on");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({504}, kSetpointRegister), Outcome::no_response);
  EXPECT_EQ(b.times_of(kRun504, asked).size(), 2u);  // the attempts the 1000 ms budget holds
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  // Should the drive have taken 504 unheard, the keep-alive puts it back on what is in force.
  b.control("silent off");
  const TimePoint after = b.rig.now();
  b.rig.run_for(1s);
  const auto next = b.frames(after);
  ASSERT_FALSE(next.empty());
  EXPECT_EQ(next.front(), kRun1149);
  EXPECT_TRUE(b.sim_has("target=0x40"));
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
}

TEST_F(MdriverWrites, ASetpointTheDriveDoesNotTakeIsRefusedAndTheOldOneStays) {
  ASSERT_TRUE(b.running_at_1149());
  // The drive answers 504 rpm (0x1C) with the target it holds, 0x40.
  b.rig.line().device_filter = [](Bytes a) {
    return a.size() == 13 && a[4] == 0x1C ? with_reply(a, 0x40, 0x00) : a;
  };
  EXPECT_EQ(b.write({504}, kSetpointRegister), Outcome::refused);
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
  EXPECT_EQ(b.read("target_code"), 0x40u);
  b.rig.run_for(1s);
  EXPECT_EQ(b.last(), kRun1149);
}

TEST_F(MdriverWrites, ACommandTheDriveRefusesIsTheExceptionAndTheRunStaysInForce) {
  ASSERT_TRUE(b.running_at_1149());
  // The drive answers the stop code with another target than the one sent.
  b.rig.line().device_filter = [](Bytes a) {
    return a.size() == 13 && a[4] == 0x01 ? with_reply(a, 0x05, 0x00) : a;
  };
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::refused);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_NE(b.read("status") & kRunning, 0u);
  b.rig.run_for(1s);
  const auto sent = b.frames(asked);
  ASSERT_GE(sent.size(), 2u);
  EXPECT_EQ(sent[0], kRunStop);
  EXPECT_EQ(sent[1], kRun1149);  // the keep-alive carries the run in force
}

TEST_F(MdriverWrites, ARunAnsweredWithAnErrorIsRefusedAndNotInForce) {
  ASSERT_EQ(b.write({1149}, kSetpointRegister), Outcome::ok);
  // The drive takes the target (R4 echoes it) but answers with error 0x04 (stall) latched.
  bool once = true;
  b.rig.line().device_filter = [&once](Bytes a) {
    if (!once || a.size() != 13 || a[4] != 0x40) return a;
    once = false;
    return with_reply(a, 0x40, 0x04);
  };
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::refused);
  EXPECT_EQ(b.read("command"), cmd::stop);
  const TimePoint after = b.rig.now();
  b.rig.run_for(1s);
  EXPECT_EQ(b.frames(after).at(0), kRunStop);  // the drive is told what is in force: stop
  EXPECT_EQ(b.read("status") & kRunning, 0u);
}

TEST_F(MdriverWrites, ARunThatGotNoAnswerIsNotInForce) {
  ASSERT_EQ(b.write({1149}, kSetpointRegister), Outcome::ok);
  b.control("silent on");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::no_response);
  // Identical attempts, each after the 200 ms reply timeout from the frame's end and the engine's
  // guard time after it: as many of the three as the default 1000 ms budget holds, two.
  const auto tries = b.times_of(kRun1149, asked);
  ASSERT_EQ(tries.size(), 2u);
  const Millis per_attempt = unanswered_attempt(kReplyTimeout) +
                             std::chrono::duration_cast<Millis>(b.on_wire(kRun1149.size()));
  EXPECT_EQ(tries[1] - tries[0], per_attempt);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("status") & kRunning, 0u);
  // The drive may have taken it unheard: the keep-alive says stop.
  b.control("silent off");
  const TimePoint after = b.rig.now();
  b.rig.run_for(1s);
  EXPECT_EQ(b.frames(after).at(0), kRunStop);
  EXPECT_TRUE(b.sim_has("target=0x01"));
  EXPECT_EQ(b.read("command"), cmd::stop);
}

}  // namespace
}  // namespace drivegate::mdriver
