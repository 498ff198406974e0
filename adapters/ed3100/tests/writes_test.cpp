// Writes as the Modbus server makes them, against the simulator on the real bus engine
// (bench.h): the document's command frames, setpoints stored or sent, parameters, and writes that
// tell the truth: a request is judged whole, and setpoint_rpm and command read what the drive
// confirmed, never what was merely asked.
#include <gtest/gtest.h>

#include "bench.h"

namespace drivegate::ed3100 {
namespace {

Bytes run_frame(std::uint16_t command, std::uint16_t reference) {
  const std::uint16_t words[] = {command, reference};
  return encode_write_multiple(0x1F, 0x2000, words);
}
Bytes reference_frame(std::uint16_t centi_hz) {
  return encode_write_single(0x1F, 0x2001, centi_hz);
}

using Ed3100Writes = test::ReadyBench<Bench>;

TEST_F(Ed3100Writes, RunForwardReverseAndStopSendTheDocumentsFrames) {
  TimePoint from = b.rig.now();
  // 42.32 Hz, the reference of the document's run examples (0x1088), written while stopped:
  // stored, the run carries it.
  EXPECT_EQ(b.write({4232}, kFrequencyRegister), Outcome::ok);
  EXPECT_TRUE(b.writes(from).empty());
  EXPECT_EQ(b.read("frequency_setpoint"), 4232u);
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 1270);  // 42.32 Hz x 120 / 4 poles

  from = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{kForward});
  EXPECT_EQ(b.rig.answers().back().bytes, kRunReply);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  ASSERT_TRUE(b.rig.run_until([&] { return b.read_i16("speed_rpm") == 1270; }, 3s));
  EXPECT_EQ(b.status() & kRunning, kRunning);
  EXPECT_EQ(b.read("running"), 1u);
  EXPECT_EQ(b.read("direction"), 0u);

  from = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_reverse}), Outcome::ok);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{kReverse});
  EXPECT_EQ(b.read("command"), cmd::run_reverse);
  ASSERT_TRUE(b.rig.run_until([&] { return b.read_i16("speed_rpm") == -1270; }, 5s));
  EXPECT_EQ(b.read("direction"), 1u);

  from = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{kStop});
  EXPECT_EQ(b.rig.answers().back().bytes, kStop);  // document: the response is the request
  EXPECT_EQ(b.read("command"), cmd::stop);
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("running") == 0; }, 3s));
  EXPECT_EQ(b.read_i16("speed_rpm"), 0);
  EXPECT_EQ(b.status() & kRunning, 0u);
}

// The document has no faster stop than 0x0001: quick_stop sends it, and what the drive then
// holds is the stop.
TEST_F(Ed3100Writes, QuickStopIsThePlainStop) {
  ASSERT_TRUE(b.running_at(1500));
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::quick_stop}), Outcome::ok);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{kStop});
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST_F(Ed3100Writes, ASetpointIsStoredWhileStoppedAndSentWhileRunning) {
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({1500}, kSetpointRegister), Outcome::ok);  // 50.00 Hz at 4 poles
  EXPECT_TRUE(b.writes(from).empty());
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 1500);
  EXPECT_EQ(b.read("frequency_setpoint"), 5000u);
  // Direction is the command's business.
  EXPECT_EQ(b.write({static_cast<std::uint16_t>(-1)}, kSetpointRegister), Outcome::invalid_value);
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 1500);

  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{run_frame(0x001E, 0x1388)});
  ASSERT_TRUE(b.rig.run_until([&] { return b.read_i16("speed_rpm") == 1500; }, 3s));

  const TimePoint running = b.rig.now();
  EXPECT_EQ(b.write({900}, kSetpointRegister), Outcome::ok);  // 30.00 Hz
  EXPECT_EQ(b.writes(running), std::vector<Bytes>{reference_frame(3000)});
  EXPECT_EQ(b.rig.answers().back().bytes, reference_frame(3000));  // the echo
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 900);
  EXPECT_EQ(b.read("frequency_setpoint"), 3000u);
  EXPECT_TRUE(b.rig.run_until([&] { return b.read_i16("speed_rpm") == 900; }, 3s));
}

// "Run reverse at 900 rpm" in one request while running forward: the setpoint first (a 06 to
// 0x2001, confirmed), then the run, carrying the reference now in force.
TEST_F(Ed3100Writes, RunAtASpeedInOneRequestWhileRunning) {
  ASSERT_TRUE(b.running_at(1500));
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_reverse, 900}), Outcome::ok);
  EXPECT_EQ(b.writes(from), (std::vector<Bytes>{reference_frame(3000), run_frame(0x002E, 3000)}));
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 900);
  EXPECT_EQ(b.read("command"), cmd::run_reverse);
  EXPECT_TRUE(b.rig.run_until([&] { return b.read_i16("speed_rpm") == -900; }, 5s));
}

// A setpoint written while a run is on its way waits for it: the run carries the reference in
// force when it left, and the new one goes to 0x2001 once the drive runs.
TEST_F(Ed3100Writes, ASetpointBehindAnUnconfirmedRunIsSentOnceTheRunIsTaken) {
  const TimePoint from = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});
  const auto speed = b.start_write({900}, kSetpointRegister);
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 0);  // not in force before the drive has it
  EXPECT_EQ(b.rig.wait(run), Outcome::ok);
  EXPECT_EQ(b.rig.wait(speed), Outcome::ok);
  EXPECT_EQ(b.writes(from), (std::vector<Bytes>{run_frame(0x001E, 0), reference_frame(3000)}));
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 900);
  EXPECT_TRUE(b.rig.run_until([&] { return b.read_i16("speed_rpm") == 900; }, 3s));
}

TEST_F(Ed3100Writes, AParameterIsWrittenWith06AndReadBack) {
  TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({0x1388}, kParam0006Register), Outcome::ok);
  b.rig.run_for(100ms);
  const auto f = b.frames(from);
  ASSERT_GE(f.size(), 2u);
  EXPECT_EQ(f[0], kWriteParam);  // the document's 06 example
  EXPECT_EQ(f[1], kReadParam);   // read back ahead of the polls
  EXPECT_EQ(b.read("param_00_06"), 0x1388u);
  EXPECT_TRUE(b.sim_has("param_00_06=0x1388"));

  // The reference and the parameter in one request: stored, and written.
  from = b.rig.now();
  EXPECT_EQ(b.write({4232, 0x1234}, kFrequencyRegister), Outcome::ok);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{encode_write_single(0x1F, 0x0006, 0x1234)});
  EXPECT_EQ(b.read("frequency_setpoint"), 4232u);
  EXPECT_EQ(b.read("param_00_06"), 0x1234u);
}

TEST_F(Ed3100Writes, ATrippedDriveRefusesARunAndAResetClearsTheTrip) {
  // The drive trips between two polls: the run goes out and its exception refuses it.
  b.control("fault 0x12");
  TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::refused);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{run_frame(0x001E, 0)});  // no resend
  EXPECT_EQ(b.rig.answers().back().bytes, encode_exception(0x1F, 0x10, 0x04));
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.status() & kRunning, 0u);
  EXPECT_EQ(b.read("retries"), 0u);

  // Once the fault word shows the trip, a run is refused without a frame.
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kFaulted) != 0; }, 1s));
  from = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_reverse}), Outcome::refused);
  b.rig.run_for(100ms);
  EXPECT_TRUE(b.writes(from).empty());

  from = b.rig.now();
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::ok);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{encode_write_single(0x1F, 0x2002, 0x0002)});
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kFaulted) == 0; }, 1s));
  EXPECT_EQ(b.read("native_fault"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// --- writes that tell the truth ---

using Ed3100TruthfulWrites = test::ReadyBench<Bench>;

// A request with a part the drive cannot take is refused whole: nothing goes on the line and no
// register changes, not even the part that alone would have been taken.
TEST_F(Ed3100TruthfulWrites, ARequestWithAnInvalidPartChangesNothing) {
  ASSERT_EQ(b.write({600}, kSetpointRegister), Outcome::ok);  // 20.00 Hz, stored

  TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, static_cast<std::uint16_t>(-100)}), Outcome::invalid_value);
  b.rig.run_for(200ms);
  EXPECT_TRUE(b.writes(from).empty());
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 600);
  EXPECT_EQ(b.read("frequency_setpoint"), 2000u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_TRUE(b.sim_has("running=0"));

  // A tripped drive cannot run: "run at 1500" is refused, and its setpoint is not stored either.
  b.control("fault 0x12");
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kFaulted) != 0; }, 1s));
  from = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward, 1500}), Outcome::refused);
  b.rig.run_for(200ms);
  EXPECT_TRUE(b.writes(from).empty());
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 600);
  EXPECT_EQ(b.read("frequency_setpoint"), 2000u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// While running, a setpoint is in force once the drive echoed it: refused, unanswered, or
// echoed with another value, setpoint_rpm keeps the value the drive confirmed before.
TEST_F(Ed3100TruthfulWrites, ASetpointTheDriveDoesNotTakeWhileRunningLeavesTheOldOne) {
  ASSERT_TRUE(b.running_at(1500));

  // Refused: the drive answers the 06 with exception 04.
  ASSERT_EQ(b.control("lock on"), "ok lock=on");
  TimePoint from = b.rig.now();
  const auto refused = b.start_write({900}, kSetpointRegister);
  ASSERT_TRUE(b.rig.run_until([&] { return !b.writes(from).empty(); }, 1s));
  // On the line, not answered yet.
  EXPECT_TRUE(b.not_yet_in_force(*refused, "setpoint_rpm", 1500));
  EXPECT_EQ(b.read("frequency_setpoint"), 5000u);
  EXPECT_EQ(b.rig.wait(refused), Outcome::refused);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{reference_frame(3000)});
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 1500);
  EXPECT_EQ(b.read("frequency_setpoint"), 5000u);
  b.rig.run_for(1s);
  EXPECT_EQ(b.read_i16("speed_rpm"), 1500);

  // Unanswered: three attempts, then 0x0B.
  b.control("lock off");
  b.control("silent on");
  from = b.rig.now();
  EXPECT_EQ(b.write({1200}, kSetpointRegister), Outcome::no_response);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>(3, reference_frame(4000)));
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 1500);
  EXPECT_EQ(b.read("frequency_setpoint"), 5000u);
  b.control("silent off");

  // Echoed with another value than the one sent: the drive did not take what was asked.
  b.rig.line().device_filter = [](Bytes reply) {
    if (reply.size() == 8 && reply[1] == kFnWriteSingle && reply[2] == 0x20 && reply[3] == 0x01) {
      reply = encode_write_single(reply[0], 0x2001, 0x1234);
    }
    return reply;
  };
  EXPECT_EQ(b.write({600}, kSetpointRegister), Outcome::refused);
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 1500);
  EXPECT_EQ(b.read("frequency_setpoint"), 5000u);
}

// A command the drive refuses on the line is the exception, and `command` keeps reading the
// command in force.
TEST_F(Ed3100TruthfulWrites, ACommandTheDriveRefusesLeavesTheCommandInForce) {
  ASSERT_TRUE(b.running_at(1500));
  ASSERT_EQ(b.control("lock on"), "ok lock=on");
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::refused);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{kStop});
  EXPECT_EQ(b.rig.answers().back().bytes, encode_exception(0x1F, 0x06, 0x04));
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.write({cmd::run_reverse}), Outcome::refused);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  b.rig.run_for(1s);
  EXPECT_EQ(b.status() & kRunning, kRunning);
  EXPECT_EQ(b.read_i16("speed_rpm"), 1500);

  b.control("lock off");
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// A trip stops the output and ends the run in force; a reset does not start the motor again.
TEST_F(Ed3100TruthfulWrites, ATripEndsTheRunInForce) {
  ASSERT_TRUE(b.running_at(1500));
  ASSERT_EQ(b.read("command"), cmd::run_forward);
  b.control("fault 0x12");
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kFaulted) != 0; }, 1s));
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.status() & kRunning, 0u);
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::ok);
  b.rig.run_for(1s);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read_i16("speed_rpm"), 0);
  EXPECT_TRUE(b.sim_has("running=0"));
}

// A run and a stop in quick succession: the stop supersedes the run still waiting for the line,
// which fails (0x0B) and never reaches the drive.
TEST_F(Ed3100TruthfulWrites, ANewerCommandSupersedesOneStillWaitingForTheLine) {
  const TimePoint from = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});
  const auto stop = b.start_write({cmd::stop});
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.rig.wait(run), Outcome::no_response);
  EXPECT_EQ(b.writes(from), std::vector<Bytes>{kStop});
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_TRUE(b.sim_has("running=0"));
}

// The port is gone while a run waits for it, and comm_lost is far off: the gateway answers 0x0B
// at its write_timeout, and when the port comes back the run is not sent after all.
TEST(Ed3100TruthfulWritesFromPowerOn, ARunThePlcWasToldFailedIsNeverSentLater) {
  Bench b({{"parameters", "00-06"}, {"comm_timeout_ms", "60000"}});
  ASSERT_TRUE(b.ready());
  b.rig.line_down();
  const TimePoint from = b.rig.now();
  const auto run = b.start_write({cmd::run_forward, 1500});
  EXPECT_EQ(b.rig.wait(run, 10s), Outcome::no_response);
  // write_timeout with the default options: 2 x (1930 ms to get on the line + 930 ms for three
  // attempts with their guard times) + 200 ms (README, "Commands and writes"), seen at the
  // gateway's next 100 ms tick.
  EXPECT_GE(b.rig.now() - from, 5920ms);
  EXPECT_LT(b.rig.now() - from, 6020ms);
  b.rig.line_up();
  b.rig.run_for(2s);
  EXPECT_TRUE(b.writes(from).empty());
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read_i16("setpoint_rpm"),
            1500);  // the request's first part, stored while stopped, was taken
  EXPECT_TRUE(b.sim_has("running=0"));
  EXPECT_EQ(b.status() & kOnline, kOnline);
}

// The same at comm_lost: the writes waiting are failed and forgotten.
TEST_F(Ed3100TruthfulWrites, CommLostFailsTheWritesWaitingAndForgetsThem) {
  b.rig.line_down();
  const TimePoint from = b.rig.now();
  const auto run = b.start_write({cmd::run_forward});
  EXPECT_EQ(b.rig.wait(run), Outcome::no_response);
  EXPECT_LT(b.rig.now() - from, 3200ms);  // comm_timeout_ms = 3000, not the write_timeout
  EXPECT_EQ(b.status() & kCommLost, kCommLost);
  b.rig.line_up();
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 10s));
  b.rig.run_for(1s);
  EXPECT_TRUE(b.writes(from).empty());
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_TRUE(b.sim_has("running=0"));
}

}  // namespace
}  // namespace drivegate::ed3100
