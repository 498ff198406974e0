// Writes as the Modbus server makes them, on the real bus engine: what goes on the wire, the
// exception the PLC gets, and what `command` and `setpoint_rpm` read afterwards. A write is in
// force once the inverter ACKed the frame that carries it without Error bits (README, "Writes").
#include <gtest/gtest.h>

#include "bench.h"

namespace drivegate::nidec {
namespace {

using NidecWrites = test::ReadyBench<Bench>;

TEST_F(NidecWrites, ASetpointWhileStoppedIsStoredThenRunForwardIsCw_5_3) {
  EXPECT_TRUE(b.runs_from_stopped(800, kCw800, 5ms));  // in force once the inverter ACKed it
  b.rig.run_for(4s);                                   // 3.0 s accel
  EXPECT_EQ(b.read("speed_rpm"), 800u);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
  EXPECT_EQ(b.last(), kPoll);  // the motion runs on; polls keep the line alive
}

TEST_F(NidecWrites, RunReverseIsCcw_5_4) {
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_reverse, 800}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kCcw800);
  EXPECT_EQ(b.read("command"), cmd::run_reverse);
  EXPECT_TRUE(b.sim_has("motion=ccw"));
}

TEST_F(NidecWrites, MotionChoosesSpinAgitationOrFreeShaft_5_5_5_6_5_14) {
  EXPECT_EQ(b.write("motion", {1}), Outcome::ok);  // spin
  EXPECT_EQ(b.read("motion"), 1u);
  // 5.6 has no direction.
  EXPECT_EQ(b.write({cmd::run_reverse, 1200}), Outcome::invalid_value);
  TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 1200}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0),
            (Bytes{0xA5, 0x0D, 0x04, 0xB0, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x02}));

  // A setpoint while spinning re-sends the motion in force, even with `motion` changed since.
  EXPECT_EQ(b.write("motion", {2}), Outcome::ok);  // agitation, for the next run
  asked = b.rig.now();
  EXPECT_EQ(b.write({60}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0),
            (Bytes{0xA5, 0x0D, 0x00, 0x3C, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x8A}));
  asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0),
            (Bytes{0xA5, 0x0C, 0x00, 0x3C, 0x05, 0x05, 0x0C, 0x08, 0x0C, 0x08, 0x95}));

  EXPECT_EQ(b.write("motion", {3}), Outcome::ok);  // free-shaft spin
  EXPECT_EQ(b.write("accel_time", {50}), Outcome::ok);
  EXPECT_EQ(b.read("accel_time"), 50u);
  asked = b.rig.now();
  EXPECT_EQ(b.write({1500}, kSetpointRegister), Outcome::ok);  // agitation in force
  EXPECT_EQ(b.frames(asked).at(0),
            (Bytes{0xA5, 0x0C, 0x05, 0xDC, 0x05, 0x05, 0x0C, 0x08, 0x0C, 0x08, 0x70}));
  asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0),
            (Bytes{0xA5, 0x1D, 0x05, 0xDC, 0x00, 0x32, 0x00, 0x00, 0x00, 0x00, 0x53}));
  EXPECT_TRUE(b.sim_has("motion=free_shaft_spin"));
  // The gateway keeps a motion the table does not name.
  EXPECT_EQ(b.write("motion", {4}), Outcome::invalid_value);
  EXPECT_EQ(b.read("motion"), 3u);
}

TEST_F(NidecWrites, AgitationTimingPoints_5_5) {
  EXPECT_EQ(b.write("motion", {2}), Outcome::ok);
  // accel 0.3 s, decel 0.4 s, CW on 2.0 s, off 1.0 s, CCW on 2.5 s, off 25.5 s, in one request.
  EXPECT_EQ(b.write("agitation_accel", {3, 4, 20, 10, 25, 255}), Outcome::ok);
  EXPECT_EQ(b.write("agitation_ccw_off", {256}), Outcome::invalid_value);  // 5.5: a byte
  EXPECT_EQ(b.read("agitation_ccw_off"), 255u);
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 100}), Outcome::ok);
  Bytes want = {0xA5, 0x0C, 0x00, 0x64, 3, 4, 20, 10, 25, 255};
  want.push_back(xor_of(want));
  EXPECT_EQ(b.frames(asked).at(0), want);
  EXPECT_EQ(b.read("agitation_ccw_on"), 25u);
}

TEST_F(NidecWrites, ASetpointWhileRunningIsInForceOnceTheInverterAckedIt_5_3) {
  ASSERT_TRUE(b.running_at(800));
  const auto w = b.start_write({1000}, kSetpointRegister);
  EXPECT_FALSE(w->settled());
  ASSERT_TRUE(b.rig.run_until([&] { return b.last() == kCw1000; }, 100ms));
  // On the wire, not answered yet: the inverter holds 800 rpm still.
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
  EXPECT_NE(b.status() & kCommandPending, 0u);
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 1000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.count(kCw1000), 1u);
  b.rig.run_for(2s);
  EXPECT_EQ(b.read("speed_rpm"), 1000u);
  // 5.3: an unsigned speed: a negative setpoint is refused before anything is sent.
  const std::size_t before = b.rig.sent().size();
  EXPECT_EQ(b.start_write({static_cast<std::uint16_t>(-1)}, kSetpointRegister)->result,
            Outcome::invalid_value);
  EXPECT_EQ(b.rig.sent().size(), before);
  EXPECT_EQ(b.read("setpoint_rpm"), 1000u);
}

TEST_F(NidecWrites, StopAndQuickStop_5_7_5_8) {
  ASSERT_TRUE(b.running_at(800));
  TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::quick_stop}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kBrake);
  EXPECT_EQ(b.read("command"), cmd::quick_stop);
  EXPECT_TRUE(b.sim_has("motion=braking"));
  asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kStop);
  EXPECT_EQ(b.read("command"), cmd::stop);
  b.rig.run_for(2s);
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  EXPECT_EQ(b.status() & kRunning, 0u);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
}

TEST_F(NidecWrites, ResetFaultAsksWhetherTheFaultCleared_section8) {
  b.control("fault general");  // section 8: kept until power off
  b.rig.run_for(5s);
  TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::refused);
  EXPECT_EQ(b.frames(asked).at(0), kPoll);  // a Request (5.2): the protocol has no reset
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::internal_error));
  EXPECT_EQ(b.read("command"), cmd::stop);
  b.control("clear");
  asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kPoll);
  EXPECT_EQ(b.read("fault_mask"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);  // a reset is no command in force
}

// --- truthful writes: what the inverter did not take is not in force ---

TEST_F(NidecWrites, ARequestWithAnInvalidPartChangesNothing) {
  ASSERT_TRUE(b.running_at(800));
  ASSERT_EQ(b.write("motion", {1}), Outcome::ok);  // spin, for the next run
  // Setpoint 1000 with run_reverse: spin has no direction. The setpoint alone would have gone on
  // the line (a run is in force); nothing does.
  std::size_t before = b.rig.sent().size();
  TimePoint asked = b.rig.now();
  EXPECT_EQ(b.start_write({cmd::run_reverse, 1000})->result, Outcome::invalid_value);
  EXPECT_EQ(b.rig.sent().size(), before);
  b.rig.run_for(1s);
  for (const Bytes& f : b.frames(asked)) EXPECT_EQ(f, kPoll);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_TRUE(b.sim_has("target_rpm=800"));

  // Stopped and faulted: run_forward is refused, so the setpoint in the same request is not
  // stored either, though alone it would have been.
  ASSERT_EQ(b.write({cmd::stop}), Outcome::ok);
  b.control("fault stall");
  ASSERT_TRUE(b.after_next_poll());
  ASSERT_NE(b.status() & kFaulted, 0u);
  before = b.rig.sent().size();
  EXPECT_EQ(b.start_write({cmd::run_forward, 600})->result, Outcome::refused);
  EXPECT_EQ(b.rig.sent().size(), before);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST_F(NidecWrites, ASetpointTheInverterRefusesLeavesTheOldOne_section8) {
  ASSERT_TRUE(b.running_at(800));
  ASSERT_TRUE(b.after_next_poll());
  // A stall between two polls: the driver does not know yet, so the new speed goes on the line
  // and its ACK carries the Error bits.
  b.control("fault stall");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({1000}, kSetpointRegister), Outcome::refused);
  EXPECT_EQ(b.frames(asked).at(0), kCw1000);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
  // Section 8: the fault stopped the motor: no run is in force.
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("native_fault"), 0x08u);
}

TEST_F(NidecWrites, ASetpointTheInverterNeverAnsweredLeavesTheOldOne_section6) {
  ASSERT_TRUE(b.running_at(800));
  ASSERT_TRUE(b.after_next_poll());
  b.control("nack 100");  // every frame refused at protocol level (5.16)
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({1000}, kSetpointRegister), Outcome::no_response);
  EXPECT_GE(b.count(kCw1000, asked), 10u);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);  // the inverter runs on at 800 rpm
  EXPECT_TRUE(b.sim_has("target_rpm=800"));
  // Not sent again once the PLC was told it failed.
  b.control("nack 0");
  const TimePoint failed = b.rig.now();
  b.rig.run_for(2s);
  EXPECT_EQ(b.count(kCw1000, failed), 0u);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);
  EXPECT_EQ(b.read("speed_rpm"), 800u);
}

TEST_F(NidecWrites, ACommandTheInverterRefusesIsTheExceptionAndCommandReadsWhatIsInForce) {
  ASSERT_TRUE(b.running_at(800));
  // A stop NACKed until it fails: the motor runs on, and so does run_forward.
  ASSERT_TRUE(b.after_next_poll());
  b.control("nack 100");
  TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::no_response);
  EXPECT_GE(b.count(kStop, asked), 10u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_NE(b.status() & kRunning, 0u);
  b.control("nack 0");
  ASSERT_TRUE(b.after_next_poll());
  EXPECT_TRUE(b.sim_has("motion=cw"));

  // A phase lost between two polls: run_reverse goes on the line and its ACK carries the Error
  // bits (section 8). Exception 0x04, and the command in force is what the fault left: stop.
  b.control("fault phase_loss");
  asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_reverse}), Outcome::refused);
  EXPECT_EQ(b.frames(asked).at(0), kCcw800);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("native_fault"), 0x40u);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::phase_loss));
  // Known now: the next run is refused before anything is sent.
  const std::size_t before = b.rig.sent().size();
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::refused);
  EXPECT_EQ(b.rig.sent().size(), before);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST_F(NidecWrites, ARunNotConfirmedIsNeverSentAfterTheFailure) {
  b.control("silent on");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 800}), Outcome::no_response);
  EXPECT_LT(b.rig.now() - asked, 3000ms);  // the driver's deadline, not the gateway's
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);  // stored while stopped, before the run was tried
  b.control("silent off");
  const TimePoint back = b.rig.now();
  b.rig.run_for(2s);
  EXPECT_EQ(b.count(kCw800, back), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_TRUE(b.sim_has("motion=stopped"));
}

TEST_F(NidecWrites, AStopOvertakesARunNotYetOnTheLine) {
  ASSERT_EQ(b.write({800}, kSetpointRegister), Outcome::ok);
  // While a poll is on the line, a run from one client and a stop from another.
  ASSERT_TRUE(b.next_poll_on_the_line());
  const std::size_t mark = b.rig.sent().size();
  const auto run = b.start_write({cmd::run_forward});
  const auto stop = b.start_write({cmd::stop});
  EXPECT_EQ(run->result, Outcome::no_response);  // superseded at once
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.frames_after(mark), std::vector<Bytes>{kStop});  // the motor never started
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST_F(NidecWrites, ASetpointQueuedBehindAStopIsStoredNotSent) {
  ASSERT_TRUE(b.running_at(800));
  // While a poll is on the line: a stop, then a new speed for the run in force now.
  ASSERT_TRUE(b.next_poll_on_the_line());
  const std::size_t mark = b.rig.sent().size();
  const auto stop = b.start_write({cmd::stop});
  const auto speed = b.start_write({1000}, kSetpointRegister);
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.rig.wait(speed), Outcome::ok);
  // Once the stop was in force the setpoint was only stored: the motor is not started again.
  EXPECT_EQ(b.frames_after(mark), std::vector<Bytes>{kStop});
  EXPECT_EQ(b.read("setpoint_rpm"), 1000u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_TRUE(b.sim_has("motion=stopping"));
}

TEST_F(NidecWrites, ASetpointWrittenWhileARunIsOnItsWayIsSentAfterIt) {
  ASSERT_EQ(b.write({800}, kSetpointRegister), Outcome::ok);
  ASSERT_TRUE(b.next_poll_on_the_line());
  const std::size_t mark = b.rig.sent().size();
  const auto run = b.start_write({cmd::run_forward});
  const auto speed = b.start_write({1000}, kSetpointRegister);
  EXPECT_FALSE(speed->settled());  // the run will carry 800 rpm: 1000 needs the line too
  EXPECT_EQ(b.rig.wait(run), Outcome::ok);
  EXPECT_EQ(b.rig.wait(speed), Outcome::ok);
  EXPECT_EQ(b.frames_after(mark), (std::vector<Bytes>{kCw800, kCw1000}));
  EXPECT_EQ(b.read("setpoint_rpm"), 1000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

}  // namespace
}  // namespace drivegate::nidec
