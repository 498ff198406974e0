// Writes as the Modbus server makes them, on the real bus engine: the frames on the wire and
// when, the exception the PLC gets, and what `command` and `setpoint_rpm` read before, during and
// after. The eDrive never acknowledges a write: a write is in force once a status read after it
// shows the drive took it (README.md, "Writes and their confirmation").
#include <gtest/gtest.h>

#include "bench.h"

namespace drivegate::unicla {
namespace {

// The write frames ("Command: Write") the master sent from `from` on.
std::vector<Sent> writes(const Bench& b, TimePoint from) {
  std::vector<Sent> out;
  for (auto& s : b.sent(from)) {
    if (s.frame.command == kWrite) out.push_back(std::move(s));
  }
  return out;
}

using UniclaWrites = test::ReadyBench<Bench>;

TEST_F(UniclaWrites, ASetpointWhileStoppedIsStoredThenTheRunGoesOutAndIsConfirmed) {
  const std::uint8_t seq = static_cast<std::uint8_t>(b.last_sequence() + 1);
  const TimePoint asked = b.rig.now();
  // At once (the line was idle): Set Run State 3000 = 0B B8, in force once the drive showed it.
  EXPECT_TRUE(b.runs_from_stopped(3000, run_state_frame(0x01, seq, 3000), kInterFrameGap));
  const auto sent = b.sent(asked);
  ASSERT_GE(sent.size(), 2u);
  EXPECT_EQ(sent[0].bytes, run_state_frame(0x01, seq, 3000));
  // Then the status read that confirmed it.
  EXPECT_EQ(sent[1].bytes, master_frame(0x01, kRead, kStatus, static_cast<std::uint8_t>(seq + 1)));
  EXPECT_GE(sent[1].at - sent[0].at, kInterFrameGap);
  EXPECT_LE(sent[1].at - sent[0].at, kInterFrameGap + b.on_wire(sent[0].bytes.size()));
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.read("op_state"), kStarting);

  ASSERT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 3000; }, 5s));
  EXPECT_EQ(b.read("op_state"), kRunningState);
  EXPECT_EQ(b.read("compressor_rpm"), 3000u);
  EXPECT_FLOAT_EQ(b.read_f32("suction_pressure"), 3.75F);  // the simulated plant follows
  EXPECT_EQ(writes(b, asked).size(), 1u);                  // one write, nothing resent

  const TimePoint stop_asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  const auto stops = writes(b, stop_asked);
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_EQ(stops[0].frame.payload, (Bytes{0x00, 0x00}));  // "a value of 0 is a stop command"
  EXPECT_EQ(b.read("command"), cmd::stop);
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 0; }, 5s));
  EXPECT_EQ(b.read("status") & kRunning, 0u);
  EXPECT_EQ(b.read("op_state"), kStopped);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);  // kept for the next run
}

// "Examples / Set Run State on Device Id 0x01": Command Speed to 1000RPM. With the sequence of the
// "CRC Example", 0x36, the CRC is 34 CC (README.md, "Frames", and codec_test.cpp).
TEST(UniclaWritesFromPowerOn, TheDocumentsSetRunStateExampleOnTheWire) {
  Bench b;
  b.control("limits 1000 6000");
  ASSERT_TRUE(b.ready());
  ASSERT_EQ(b.write({1000}, kSetpointRegister), Outcome::ok);
  // Polls until the frame before the write carries sequence 0x35.
  ASSERT_TRUE(b.rig.run_until([&] { return b.last_sequence() == 0x35; }, 60s));
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  const auto w = writes(b, asked);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_EQ(w[0].bytes, (Bytes{0x7E, 0x00, 0x01, 0xC1, 0xC0, 0x36, 0x00, 0x00, 0x02, 0x03, 0xE8,
                               0x34, 0xCC, 0x7E}));
}

TEST_F(UniclaWrites, ASpeedChangeWhileRunningIsInForceOnceTheSpeedShowsIt) {
  ASSERT_TRUE(b.running_at(3000));
  const TimePoint asked = b.rig.now();
  const auto w = b.start_write({4500}, kSetpointRegister);
  ASSERT_TRUE(b.rig.run_until([&] { return !writes(b, asked).empty(); }, 100ms));
  // On the wire, not yet shown: the drive holds 3000 rpm still.
  EXPECT_FALSE(w->settled());
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 4500u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].frame.payload, (Bytes{0x11, 0x94}));  // 4500
  // Decided within a confirmation poll or two of the drive moving, not at the 500 ms poll.
  EXPECT_LE(b.rig.now() - sent[0].at, 250ms);
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 4500; }, 5s));
}

// A PLC writes "setpoint, run_forward" in one request. While running, the setpoint goes out and
// is confirmed, then the run finds the drive running at it: one frame for the request.
TEST_F(UniclaWrites, SetpointAndRunTogetherWhileRunningCostOneFrame) {
  ASSERT_TRUE(b.running_at(3000));
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 4500}), Outcome::ok);
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].frame.payload, (Bytes{0x11, 0x94}));
  EXPECT_EQ(b.read("setpoint_rpm"), 4500u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  // The same request again, every PLC cycle: the drive holds it already, nothing to send.
  const TimePoint again = b.rig.now();
  EXPECT_EQ(b.start_write({cmd::run_forward, 4500})->result, Outcome::ok);
  b.rig.run_for(1s);
  EXPECT_TRUE(writes(b, again).empty());
}

TEST_F(UniclaWrites, SetpointZeroWhileRunningIsAStop) {
  ASSERT_TRUE(b.running_at(3000));
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({0}, kSetpointRegister), Outcome::ok);
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].frame.payload, (Bytes{0x00, 0x00}));  // "treated as a stop command"
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::invalid_value);  // nothing to run at
}

TEST_F(UniclaWrites, QuickStopIsAPlainStop) {
  ASSERT_TRUE(b.running_at(3000));
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::quick_stop}), Outcome::ok);
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0].frame.payload, (Bytes{0x00, 0x00}));  // the protocol has one stop
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST_F(UniclaWrites, AStopAlwaysGoesOnTheLine) {
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);  // stopped already: told again all the same
  ASSERT_EQ(writes(b, asked).size(), 1u);
}

TEST(UniclaWritesFromPowerOn, OutOfLimitsAndImpossibleWritesAreRefusedWithoutAFrame) {
  Bench b;
  // Before the running limits are read a speed cannot be judged.
  EXPECT_EQ(b.start_write({3000}, kSetpointRegister)->result, Outcome::refused);
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::refused);
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
  ASSERT_TRUE(b.ready());
  const std::size_t before = b.rig.sent().size();
  const TimePoint from = b.rig.now();
  const auto at_once = [&](std::vector<std::uint16_t> values, std::uint16_t address) {
    return b.start_write(std::move(values), address)->result;
  };
  // "between the configured min and max reported by eDrive": 1500..6000 in the simulator.
  EXPECT_EQ(at_once({7000}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(at_once({1000}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(at_once({static_cast<std::uint16_t>(-5)}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(at_once({cmd::run_reverse}, kCommandRegister), Outcome::invalid_value);
  EXPECT_EQ(at_once({cmd::run_forward}, kCommandRegister), Outcome::invalid_value);  // at 0
  EXPECT_EQ(at_once({cmd::run_forward, 7000}, kCommandRegister), Outcome::invalid_value);
  EXPECT_EQ(b.rig.sent().size(), before);
  b.rig.run_for(1s);
  EXPECT_TRUE(writes(b, from).empty());
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  // The limits themselves are taken.
  EXPECT_EQ(at_once({6000}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(at_once({1500}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 1500u);
}

TEST_F(UniclaWrites, AMotorFaultRefusesARunAndResetFaultClearsIt) {
  ASSERT_TRUE(b.running_at(3000));
  b.control("fault motor");  // Fault - Motor + ST Motor Control - Over Current
  b.rig.run_for(600ms);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::over_current));
  EXPECT_EQ(b.read("native_fault"), kFaultMotor);
  EXPECT_EQ(b.read("motor_safety_run"), 0x4000u);
  // The run in force stays the command in force: the drive tripped, nobody told it to stop.
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  // A run: sent, and the status after it shows the fault: refused.
  TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 3000}), Outcome::refused);
  ASSERT_EQ(writes(b, asked).size(), 1u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);

  asked = b.rig.now();
  const std::uint8_t seq = static_cast<std::uint8_t>(b.last_sequence() + 1);
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::ok);
  const auto acks = writes(b, asked);
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].bytes, master_frame(0x01, kWrite, kAck, seq));  // "Acknowledge Faults: 0"
  EXPECT_EQ(b.read("fault_code"), 0u);
  EXPECT_EQ(b.read("native_fault"), 0u);
  EXPECT_EQ(b.read("op_state"), kStopped);
  EXPECT_EQ(b.read("status") & kFaulted, 0u);
  // And it runs again.
  EXPECT_EQ(b.write({cmd::run_forward, 3000}), Outcome::ok);
  EXPECT_NE(b.read("status") & kRunning, 0u);
}

TEST_F(UniclaWrites, AnAcknowledgeThatDoesNotClearIsRefusedAtTheDeadline) {
  b.control("sticky on");
  b.control("fault pressure");
  b.rig.run_for(600ms);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::process_limit));
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::refused);
  // confirm_timeout_ms after it was written, statuses having shown the fault standing.
  EXPECT_EQ(b.rig.now() - asked, 2000ms);
  EXPECT_EQ(writes(b, asked).size(), 1u);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::process_limit));
}

TEST(UniclaWritesFromPowerOn, ControlDisabledRefusesWritesWithoutAFrame) {
  Bench b;
  b.control("control off");
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.read("control_enabled"), 0u);
  EXPECT_EQ(b.write({3000}, kSetpointRegister), Outcome::ok);  // stored, nothing sent
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::refused);
  EXPECT_EQ(b.start_write({cmd::stop})->result, Outcome::refused);
  EXPECT_EQ(b.start_write({cmd::reset_fault})->result, Outcome::refused);
  b.rig.run_for(1s);
  EXPECT_TRUE(writes(b, from).empty());
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// Two clients: the second write comes while the first is still unconfirmed.
TEST_F(UniclaWrites, AStopOvertakesAnUnconfirmedSpeedChange) {
  ASSERT_TRUE(b.running_at(3000));
  const TimePoint asked = b.rig.now();
  const auto speed = b.start_write({4500}, kSetpointRegister);
  const auto stop = b.start_write({cmd::stop});
  EXPECT_EQ(speed->result, Outcome::no_response);  // superseded
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);  // 4500 was never in force
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 1u);  // the speed change never reached the line
  EXPECT_EQ(sent[0].frame.payload, (Bytes{0x00, 0x00}));
  // Stop in force: a setpoint now is stored, not sent (it must not start the drive).
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 0; }, 5s));
  const TimePoint later = b.rig.now();
  EXPECT_EQ(b.start_write({2000}, kSetpointRegister)->result, Outcome::ok);
  b.rig.run_for(1s);
  EXPECT_TRUE(writes(b, later).empty());
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  EXPECT_EQ(b.read("setpoint_rpm"), 2000u);
}

TEST_F(UniclaWrites, ASetpointBehindAnUnconfirmedRunWaitsItsTurn) {
  ASSERT_EQ(b.write({3000}, kSetpointRegister), Outcome::ok);
  const TimePoint asked = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});
  const auto speed = b.start_write({4000}, kSetpointRegister);
  EXPECT_FALSE(speed->settled());
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.rig.wait(run), Outcome::ok);
  EXPECT_EQ(b.rig.wait(speed), Outcome::ok);
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].frame.payload, (Bytes{0x0B, 0xB8}));  // the run at 3000 first
  EXPECT_EQ(sent[1].frame.payload, (Bytes{0x0F, 0xA0}));  // then 4000, once it ran
  EXPECT_EQ(b.read("setpoint_rpm"), 4000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

TEST_F(UniclaWrites, TheSameWriteFromTwoClientsSharesOneFrame) {
  ASSERT_TRUE(b.running_at(3000));
  const TimePoint asked = b.rig.now();
  const auto one = b.start_write({cmd::stop});
  const auto two = b.start_write({cmd::stop});
  EXPECT_EQ(b.rig.wait(one), Outcome::ok);
  EXPECT_EQ(b.rig.wait(two), Outcome::ok);
  EXPECT_EQ(writes(b, asked).size(), 1u);
}

// --- truthful writes: what the drive has not shown it took is not in force ---

// The issue's own example: FC 0x10 writing command = run_reverse and setpoint_rpm = 1500 to an
// eDrive answered 0x03 and left the setpoint at 1500.
TEST_F(UniclaWrites, TheIssuesExampleRunReverseWithASetpointChangesNothing) {
  ASSERT_EQ(b.write({3000}, kSetpointRegister), Outcome::ok);
  const std::size_t before = b.rig.sent().size();
  const TimePoint asked = b.rig.now();
  // Holding 0..1: run_reverse, 1500 (in the simulator's limits, so valid on its own).
  EXPECT_EQ(b.start_write({cmd::run_reverse, 1500})->result, Outcome::invalid_value);
  EXPECT_EQ(b.rig.sent().size(), before);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  b.rig.run_for(1s);
  EXPECT_TRUE(writes(b, asked).empty());
  EXPECT_TRUE(b.sim_has("target=0"));
}

TEST_F(UniclaWrites, ARequestWithAnInvalidOrRefusedPartChangesNothing) {
  ASSERT_TRUE(b.running_at(3000));
  const TimePoint asked = b.rig.now();
  const std::size_t before = b.rig.sent().size();
  // A setpoint the drive could take, with a command it cannot: the setpoint alone would have
  // gone on the line.
  EXPECT_EQ(b.start_write({cmd::run_reverse, 4500})->result, Outcome::invalid_value);
  // A command it could take, with a setpoint out of its limits.
  EXPECT_EQ(b.start_write({cmd::stop, 7000})->result, Outcome::invalid_value);
  EXPECT_EQ(b.rig.sent().size(), before);
  b.rig.run_for(1s);
  EXPECT_TRUE(writes(b, asked).empty());
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.read("speed_rpm"), 3000u);

  // Before the limits are known: the setpoint of "run at 3000" cannot be judged, so neither part
  // is applied (0x04), and not even the setpoint is stored.
  Bench fresh;
  EXPECT_EQ(fresh.start_write({cmd::run_forward, 3000})->result, Outcome::refused);
  EXPECT_EQ(fresh.read("setpoint_rpm"), 0u);
  EXPECT_EQ(fresh.read("command"), cmd::stop);
}

TEST_F(UniclaWrites, ASetpointTheDriveDoesNotTakeLeavesTheOldOneInForce) {
  ASSERT_TRUE(b.running_at(3000));
  // The drive's own limits change behind the gateway's back: it now ignores 5000.
  b.control("limits 1500 4000");
  const TimePoint asked = b.rig.now();
  const auto w = b.start_write({5000}, kSetpointRegister);
  ASSERT_TRUE(b.rig.run_until([&] { return !writes(b, asked).empty(); }, 100ms));
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.rig.wait(w), Outcome::no_response);
  // confirm_timeout_ms after it was written.
  EXPECT_EQ(b.rig.now() - asked, 2000ms);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.read("speed_rpm"), 3000u);
  // Meanwhile the status was read every 100 ms, not every 500: the drive had every chance.
  // The first right after the write (asked for as it went out, sent after the gap), each next one
  // kConfirmPoll after the one before was asked for.
  const auto sent = b.sent(asked);
  ASSERT_GE(sent.size(), 3u);
  EXPECT_EQ(sent[0].frame.message_id, kRunState);
  EXPECT_EQ(sent[1].frame.message_id, kStatus);
  EXPECT_GE(sent[1].at - sent[0].at, kInterFrameGap);
  EXPECT_LE(sent[1].at - sent[0].at, kInterFrameGap + b.on_wire(sent[0].bytes.size()));
  EXPECT_EQ(sent[2].at - sent[0].at, kConfirmPoll);
  std::size_t reads = 1;
  for (std::size_t i = 2; i < sent.size() && sent[i].at < asked + 2000ms; ++i) {
    EXPECT_EQ(sent[i].frame.message_id, kStatus);
    if (i > 2) {
      EXPECT_EQ(sent[i].at - sent[i - 1].at, kConfirmPoll) << i;
    }
    ++reads;
  }
  EXPECT_EQ(reads, 20u);                   // 5 ms, then every 100 ms up to the deadline
  EXPECT_EQ(writes(b, asked).size(), 1u);  // nothing undone: a speed change is never retried
}

TEST_F(UniclaWrites, ARunTheDriveRefusesIsTheExceptionAndIsUndone) {
  ASSERT_EQ(b.write({3000}, kSetpointRegister), Outcome::ok);
  b.control("fault 12");  // Locked: no run
  b.rig.run_for(600ms);
  const TimePoint asked = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});
  ASSERT_TRUE(b.rig.run_until([&] { return !writes(b, asked).empty(); }, 100ms));
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.rig.wait(run), Outcome::refused);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  // Refused by the first status after it, then told stop, so that the drive does not start on
  // its own once it is no longer Locked: the PLC was told the run did not happen.
  b.rig.run_for(300ms);
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[0].frame.payload, (Bytes{0x0B, 0xB8}));
  EXPECT_EQ(sent[1].frame.payload, (Bytes{0x00, 0x00}));
  b.control("clear");
  b.rig.run_for(1s);
  EXPECT_EQ(b.read("status") & kRunning, 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST_F(UniclaWrites, ARunTheDriveIgnoresIsNotInForceAndIsUndone) {
  ASSERT_EQ(b.write({3000}, kSetpointRegister), Outcome::ok);
  b.control("control off");  // the drive now ignores every write; the gateway cannot know
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::no_response);
  EXPECT_EQ(b.rig.now() - asked, 2000ms);
  EXPECT_EQ(b.read("command"), cmd::stop);
  b.rig.run_for(100ms);
  const auto sent = writes(b, asked);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_EQ(sent[1].frame.payload, (Bytes{0x00, 0x00}));
  EXPECT_LE(sent[1].at - (asked + 2000ms), kInterFrameGap + 50ms);
}

TEST_F(UniclaWrites, AWriteToADriveThatFallsSilentFailsAndCommLostRefusesTheNext) {
  ASSERT_EQ(b.write({3000}, kSetpointRegister), Outcome::ok);
  b.control("silent on");
  const TimePoint asked = b.rig.now();
  // The drive takes the run but never answers a read: not shown within confirm_timeout_ms. The
  // verdict comes once the read on the line when the deadline passed has had its attempts.
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::no_response);
  EXPECT_GE(b.rig.now() - asked, 2000ms);
  EXPECT_LE(b.rig.now() - asked, 2000ms + 3 * 206ms);  // attempts with their guard times
  EXPECT_EQ(b.read("command"), cmd::stop);
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->comm_lost(); }, 10s));
  const std::size_t before = b.rig.sent().size();
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::no_response);
  EXPECT_EQ(b.rig.sent().size(), before);
  b.control("silent off");
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 10s));
  // What is in force survived: the setpoint, and stop.
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

}  // namespace
}  // namespace drivegate::unicla
