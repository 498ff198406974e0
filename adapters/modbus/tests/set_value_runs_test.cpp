// A drive its set value runs (`setpoint_rpm = { ..., runs = true }`: an EC fan, a BLDC driver with
// no run command), on the real bus engine against the simulator (tests/support/adapter_bench.h):
// a setpoint written while no run is in force is held by the gateway and never reaches the drive;
// run_forward writes it, stop writes 0; a run with nothing to run at is refused; a reset with no
// run in force writes 0 first, so a cleared trip does not restart the motor. Asserted on the
// frames the master sent and on the registers a PLC reads.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <variant>
#include <vector>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "common_block.h"
#include "profile.h"
#include "profile_support.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;
using testing::ElementsAre;
using testing::HasSubstr;

constexpr std::uint16_t kSetValue = 1;
constexpr std::uint16_t kReset = 0;

// The values the master wrote to holding `address` with FC 06, from `from` on, in order.
std::vector<std::uint16_t> written(const test::AdapterBench& b, std::uint16_t address,
                                   TimePoint from) {
  std::vector<std::uint16_t> out;
  for (const Bytes& f : b.frames(from)) {
    if (f.size() == 8 && f[1] == 0x06 && ((f[2] << 8) | f[3]) == address) {
      out.push_back(static_cast<std::uint16_t>((f[4] << 8) | f[5]));
    }
  }
  return out;
}

struct Fan {
  explicit Fan(const std::string& profile = support::kFanProfile) : file{profile, "fan.toml"} {}

  support::ProfileFile file;
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};

  [[nodiscard]] std::vector<std::uint16_t> written(std::uint16_t address, TimePoint from) const {
    return modbus_device::written(b, address, from);
  }
  bool turning() { return b.sim_has("running"); }
  bool speed_is(std::uint32_t rpm) {
    return b.rig.run_until([&] { return b.read("speed_rpm") == rpm; }, 2s);
  }
  // Replies late and the trip raised, until the read of the status (input 16..17) that carries
  // the trip is on the line, its reply not back yet.
  testing::AssertionResult tripped_with_its_read_on_the_line() {
    if (b.control("late 40").rfind("ok", 0) != 0 || b.control("fault 1").rfind("ok", 0) != 0) {
      return testing::AssertionFailure() << "the simulator refused late / fault";
    }
    const std::size_t mark = b.rig.sent().size();
    const auto status_read = [&] {
      for (const Bytes& fr : b.frames_after(mark)) {
        if (fr.size() == 8 && fr[1] == 0x04 && ((fr[2] << 8) | fr[3]) == 16) return true;
      }
      return false;
    };
    if (!b.rig.run_until(status_read, 2s)) return testing::AssertionFailure() << "no status read";
    return testing::AssertionSuccess();
  }
  // Running at 1000 rpm, the fan trips; the PLC (the bench's client) reads the fault, and the
  // trip's own stop is written.
  testing::AssertionResult tripped_and_read_by_the_plc() {
    if (const auto running = running_at(1000); !running) return running;
    if (b.control("fault 1").rfind("ok", 0) != 0) return testing::AssertionFailure() << "fault 1";
    if (!b.rig.run_until([&] { return (b.status() & kFaulted) != 0; }, 2s)) {
      return testing::AssertionFailure() << "no trip read";
    }
    b.rig.run_for(1s);
    return testing::AssertionSuccess();
  }
  // Online, then run at `rpm` in one request (command and setpoint), turning at it.
  testing::AssertionResult running_at(std::uint16_t rpm) {
    if (!b.until_online()) return testing::AssertionFailure() << "not online";
    if (b.write({cmd::run_forward, rpm}) != Outcome::ok) {
      return testing::AssertionFailure() << "run at " << rpm << " not taken";
    }
    if (!speed_is(rpm)) return testing::AssertionFailure() << "speed_rpm " << b.read("speed_rpm");
    return testing::AssertionSuccess();
  }
};

TEST(ModbusSetValueRuns, ASetpointWrittenWhileStoppedIsHeldAndNeverReachesTheDrive) {
  Fan f;
  ASSERT_TRUE(f.b.until_online());
  const TimePoint from = f.b.rig.now();
  EXPECT_EQ(f.b.write({1000}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 1000u);
  f.b.rig.run_for(2s);
  EXPECT_TRUE(f.written(kSetValue, from).empty());
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.status() & kRunning, 0u);
  EXPECT_EQ(f.b.read("speed_rpm"), 0u);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 1000u);
  EXPECT_EQ(f.b.read("command"), cmd::stop);
}

TEST(ModbusSetValueRuns, RunWritesTheHeldSetpointAndStopWritesZero) {
  Fan f;
  ASSERT_TRUE(f.b.until_online());
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.write({1000}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(f.b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{1000});
  EXPECT_EQ(f.b.read("command"), cmd::run_forward);
  EXPECT_TRUE(f.speed_is(1000));
  EXPECT_NE(f.b.status() & kRunning, 0u);
  ASSERT_EQ(f.b.write({cmd::stop}), Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), (std::vector<std::uint16_t>{1000, 0}));
  EXPECT_TRUE(f.speed_is(0));
  EXPECT_FALSE(f.turning());
  // The setpoint stays the gateway's, for the next run.
  EXPECT_EQ(f.b.read("setpoint_rpm"), 1000u);
}

// The common block's command and setpoint in one FC 16 (holding 0..1): the run goes at that
// setpoint, though the command is the first register of the two.
TEST(ModbusSetValueRuns, ACommandAndASetpointInOneRequestRunAtThatSetpoint) {
  Fan f;
  ASSERT_TRUE(f.b.until_online());
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.write({cmd::run_forward, 1200}), Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{1200});
  EXPECT_TRUE(f.speed_is(1200));
  EXPECT_EQ(f.b.read("setpoint_rpm"), 1200u);
}

// Nothing to run at: refused (0x04), nothing written, the fan still.
TEST(ModbusSetValueRuns, ARunWithNoSetpointIsRefusedAndNothingIsSent) {
  Fan f;
  ASSERT_TRUE(f.b.until_online());
  const TimePoint from = f.b.rig.now();
  EXPECT_EQ(f.b.write({cmd::run_forward}), Outcome::refused);
  EXPECT_EQ(f.b.write({cmd::run_forward, 0}), Outcome::refused);
  f.b.rig.run_for(1s);
  EXPECT_TRUE(f.written(kSetValue, from).empty());
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  // A set value says no direction.
  EXPECT_EQ(f.b.write({cmd::run_reverse, 1000}), Outcome::invalid_value);
  EXPECT_TRUE(f.written(kSetValue, from).empty());
}

TEST(ModbusSetValueRuns, ASetpointWhileRunningGoesToTheDriveAndIsConfirmed) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  const TimePoint from = f.b.rig.now();
  EXPECT_EQ(f.b.write({600}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{600});
  EXPECT_TRUE(f.speed_is(600));
  EXPECT_EQ(f.b.read("setpoint_rpm"), 600u);
}

// The fan trips while running: the run in force is over (command stop), and the driver writes its
// set value 0 itself, so that the fault clearing by itself (a locked rotor freed, the mains back)
// does not restart the fan while the PLC reads stop. The setpoint stays the gateway's.
TEST(ModbusSetValueRuns, ATripStopsTheFanSoThatItsClearingNeverRestartsIt) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) != 0; }, 2s));
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  EXPECT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, from).empty(); }, 1s));
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{0});
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);  // cleared by the fan itself
  EXPECT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) == 0; }, 2s));
  f.b.rig.run_for(2s);
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.read("speed_rpm"), 0u);
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 1000u);
}

// The same while the tripped fan still coasts: with no run bit, a speed not 0 reads as running,
// but a fault shown ends its run all the same.
TEST(ModbusSetValueRuns, ATripWhileTheFanStillCoastsEndsTheRunAllTheSame) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  ASSERT_EQ(f.b.control("set actual_speed 800").rfind("ok", 0), 0u);  // coasting
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) != 0; }, 2s));
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  EXPECT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, from).empty(); }, 1s));
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{0});
}

// The driver's own stop after a trip goes unanswered (the set value's register muted): it is owed
// and written again once the fan answers, so the fault clearing later does not restart the fan.
TEST(ModbusSetValueRuns, AStopAfterATripThatFailsIsWrittenAgain) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.control("mute holding 1 on").rfind("ok", 0), 0u);
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) != 0; }, 2s));
  f.b.rig.run_for(2s);
  ASSERT_FALSE(f.written(kSetValue, from).empty()) << "the stop was tried";
  ASSERT_EQ(f.b.control("mute holding 1 off").rfind("ok", 0), 0u);
  f.b.rig.run_for(2s);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  f.b.rig.run_for(2s);
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.read("speed_rpm"), 0u);
  EXPECT_EQ(f.b.read("command"), cmd::stop);
}

// A client's stop waiting for the line when the trip is shown is the stop owed: it is written and
// answered ok, and the driver adds none of its own.
TEST(ModbusSetValueRuns, AClientsStopWaitingAtATripIsWrittenAndAnsweredOk) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  ASSERT_TRUE(f.tripped_with_its_read_on_the_line());
  const TimePoint from = f.b.rig.now();
  const auto stop = f.b.start_write({cmd::stop});
  ASSERT_TRUE(f.b.rig.run_until([&] { return stop->settled(); }, 3s));
  EXPECT_EQ(stop->result, Outcome::ok);
  f.b.rig.run_for(1s);
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{0});
  EXPECT_FALSE(f.turning());
}

// "Reset, then run" in quick succession after a trip: neither overtakes the other; the reset is
// written whole and the run starts the fan at its setpoint.
TEST(ModbusSetValueRuns, AResetThenARunAreBothCarriedOut) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) != 0; }, 2s));
  f.b.rig.run_for(1s);  // the driver's own stop is written
  ASSERT_EQ(f.b.control("late 40").rfind("ok", 0),
            0u);  // the run comes while the reset is on the line
  const TimePoint from = f.b.rig.now();
  const auto reset = f.b.start_write({cmd::reset_fault});
  ASSERT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, from).empty(); }, 1s));
  const auto run = f.b.start_write({cmd::run_forward});
  ASSERT_TRUE(f.b.rig.run_until([&] { return reset->settled() && run->settled(); }, 3s));
  EXPECT_EQ(reset->result, Outcome::ok);
  EXPECT_EQ(run->result, Outcome::ok);
  EXPECT_EQ(f.written(kReset, from), std::vector<std::uint16_t>{4});
  EXPECT_EQ(f.written(kSetValue, from), (std::vector<std::uint16_t>{0, 1000}));
  EXPECT_TRUE(f.speed_is(1000));
  EXPECT_EQ(f.b.read("command"), cmd::run_forward);
}

// Running at 1000 rpm, the fan trips with `fault` (a simulator's fault number) and stays tripped;
// a PLC re-sends run every 500 ms. The trip's own stop is written once; the runs asked with the
// trip shown are written as asked and the trip does not end them: no 0 after the first of them.
void expect_runs_resent_through_a_trip_not_stopped(Fan& f, const std::string& fault) {
  ASSERT_TRUE(f.running_at(1000));
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.control("fault " + fault).rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) != 0; }, 2s));
  ASSERT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, from).empty(); }, 1s));
  for (int cycle = 0; cycle < 8; ++cycle) {
    EXPECT_EQ(f.b.write({cmd::run_forward}), Outcome::ok) << "cycle " << cycle;
    f.b.rig.run_for(500ms);
  }
  const auto values = f.written(kSetValue, from);
  ASSERT_GE(values.size(), 2u);
  EXPECT_EQ(values.front(), 0u) << "the trip's own stop";
  EXPECT_THAT(std::vector<std::uint16_t>(values.begin() + 1, values.end()), testing::Each(1000u))
      << "no 0 after the first run asked with the trip shown";
  EXPECT_EQ(f.b.read("command"), cmd::run_forward);
  EXPECT_NE(f.b.status() & kFaulted, 0u);
}

// A PLC that re-sends run each cycle to a fan whose trip stays: the trip's own stop is written
// once; the runs asked with the trip shown are written as asked and the trip does not end them, so
// the set value is not written and stopped in turn. The fan runs once the fault clears, as the
// command the PLC reads (run) says.
TEST(ModbusSetValueRuns, ARunResentWhileTheTripStaysIsNotStoppedEachCycle) {
  Fan f;
  expect_runs_resent_through_a_trip_not_stopped(f, "1");
  ASSERT_FALSE(testing::Test::HasFatalFailure());
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  EXPECT_TRUE(f.speed_is(1000));
}

// The same where the fault's code is a sensor's (ebm-papst's Hall error): a fault shown all the
// same, which ends a run in force; the run asked with it shown is not ended by it either.
TEST(ModbusSetValueRuns, ARunResentWhileASensorFaultStaysIsNotStoppedEachCycle) {
  Fan f{support::replaced(
      support::kFanProfile, "fault = { point = \"motor_status\", bit = 4 }\n",
      "fault = { point = \"motor_status\", bit = 4 }\n"
      "fault_code = { point = \"motor_status\", bits = { 4 = \"sensor_fault\" } }\n")};
  expect_runs_resent_through_a_trip_not_stopped(f, "16");  // motor_status bit 4
}

// A request of setpoint and run sent before the trip showed, its run applied after: the read that
// shows the trip is on the line when the request comes, its setpoint part waits for the line and
// is then held (no run in force any more), and only then is the run part applied. Asked before
// the trip, the run is over (no_response) like one that waited in the driver when the trip
// showed: it never overtakes the stop the trip owes, and the fault clearing at once, before
// another read, never restarts the fan.
TEST(ModbusSetValueRuns, ARunAskedBeforeTheTripShowedIsEndedByIt) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  ASSERT_TRUE(f.tripped_with_its_read_on_the_line());
  const TimePoint from = f.b.rig.now();
  const auto request = f.b.start_write({cmd::run_forward, 1200});
  ASSERT_TRUE(f.b.rig.run_until([&] { return request->settled(); }, 3s));
  EXPECT_EQ(request->result, Outcome::no_response);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);  // cleared before another read
  f.b.rig.run_for(2s);
  // The setpoint part may reach the fan while its run still reads in force (the read showing the
  // trip is not published until its cycle ends); the last value written is the trip's stop.
  const auto values = f.written(kSetValue, from);
  ASSERT_FALSE(values.empty());
  EXPECT_EQ(values.back(), 0u);
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.read("speed_rpm"), 0u);
}

// Whether a client that keeps no record of its reads (test::BusRig::kMaintain) reads the fault
// bit: what the fan shows, without the PLC having read it.
bool onlooker_sees_a_fault(Fan& f) {
  const auto r =
      f.b.rig.read(*f.b.drive, Table::input, kStatusRegister, 1, test::BusRig::kMaintain);
  return !r.empty() && (r[0] & kFaulted) != 0;
}

// Running at 1000 rpm, the fan trips and its own stop is written, while the PLC (the bench's
// client) reads nothing of the fault state: an onlooker, a client that keeps no record of its
// reads, watches the fault bit instead.
testing::AssertionResult tripped_unread_by_the_plc(Fan& f) {
  if (const auto running = f.running_at(1000); !running) return running;
  if (f.b.control("fault 1").rfind("ok", 0) != 0) return testing::AssertionFailure() << "fault 1";
  if (!f.b.rig.run_until([&] { return onlooker_sees_a_fault(f); }, 2s)) {
    return testing::AssertionFailure() << "no trip shown";
  }
  f.b.rig.run_for(1s);  // the trip's own stop is written
  return testing::AssertionSuccess();
}

// The trip shown, the PLC asks for run without having read it: its run is over (no_response),
// nothing is written, the command reads stop, and the fault clearing does not restart the fan.
void expect_the_plcs_run_over_and_the_fan_kept_still(Fan& f) {
  const TimePoint from = f.b.rig.now();
  EXPECT_EQ(f.b.write({cmd::run_forward}), Outcome::no_response);
  f.b.rig.run_for(1s);
  EXPECT_THAT(f.written(kSetValue, from), testing::IsEmpty());
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  f.b.rig.run_for(2s);
  EXPECT_FALSE(f.turning());
}

// The trip shown, but the PLC has not read it (it polls the speed only, or its run was sent
// before the trip and read from the socket after it): its run is not a choice made with the trip
// in view. It is over (no_response) as a run asked before the trip, the trip's stop stands, and
// the fault clearing does not restart the fan.
TEST(ModbusSetValueRuns, ARunFromAClientThatHadNotReadTheTripIsEndedByIt) {
  Fan f;
  ASSERT_TRUE(tripped_unread_by_the_plc(f));
  expect_the_plcs_run_over_and_the_fan_kept_still(f);
  EXPECT_EQ(f.b.read("speed_rpm"), 0u);
}

// The PLC read a first trip; the fault cleared and the fan tripped again, neither read by the
// PLC. The fault it saw is not this trip: its run is over (no_response), the fan stays stopped.
TEST(ModbusSetValueRuns, ARunFromAClientThatReadOnlyAnEarlierTripIsEndedByTheNewOne) {
  Fan f;
  ASSERT_TRUE(f.tripped_and_read_by_the_plc());
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return !onlooker_sees_a_fault(f); }, 2s));
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return onlooker_sees_a_fault(f); }, 2s));
  expect_the_plcs_run_over_and_the_fan_kept_still(f);
}

// What counts is what the asking client read: of two clients sending the same run in the same
// trip, the one that had not read the fault is refused the exemption (no_response) and the one
// that had is taken (ok): the command reads run, and the fan runs once the fault clears.
TEST(ModbusSetValueRuns, OnlyTheClientThatReadTheTripRunsThroughIt) {
  Fan f;
  ASSERT_TRUE(tripped_unread_by_the_plc(f));
  const Session reader{
      AccessLevel::operate, WordOrder::big, true, {}, std::make_shared<FaultReads>()};
  ASSERT_NE(f.b.rig.read(*f.b.drive, Table::input, kStatusRegister, 1, reader).at(0) & kFaulted,
            0u);
  const TimePoint from = f.b.rig.now();
  EXPECT_EQ(f.b.write({cmd::run_forward}), Outcome::no_response);  // the PLC: not read
  EXPECT_EQ(f.b.rig.write_and_wait(*f.b.drive, Table::holding, kCommandRegister, {cmd::run_forward},
                                   5s, reader),
            Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{1000});
  EXPECT_EQ(f.b.read("command"), cmd::run_forward);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  EXPECT_TRUE(f.speed_is(1000));
}

// A comm loss ends that exemption: the fault read once the line is back may be another trip, come
// unseen while the line was down. The run asked with the first one shown is ended by it, and its
// stop written, so the fault clearing then does not restart the fan.
TEST(ModbusSetValueRuns, ACommLossEndsTheExemptionOfARunAskedInATrip) {
  Fan f;
  ASSERT_TRUE(f.tripped_and_read_by_the_plc());
  ASSERT_EQ(f.b.write({cmd::run_forward}), Outcome::ok);
  f.b.rig.run_for(1s);
  ASSERT_EQ(f.b.read("command"), cmd::run_forward);  // asked in the trip: not ended by it
  ASSERT_EQ(f.b.control("silent on").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kCommLost) != 0; }, 30s));
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.control("silent off").rfind("ok", 0), 0u);
  EXPECT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, from).empty(); }, 10s));
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{0});
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  f.b.rig.run_for(2s);
  EXPECT_FALSE(f.turning());
}

// The run asked with a trip shown outlives that trip only: once a read shows the fault gone, a
// new trip ends it and the driver writes the stop, as for any run.
TEST(ModbusSetValueRuns, ARunAskedInATripIsEndedByTheNextTrip) {
  Fan f;
  ASSERT_TRUE(f.tripped_and_read_by_the_plc());
  ASSERT_EQ(f.b.write({cmd::run_forward}), Outcome::ok);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.speed_is(1000));
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) != 0; }, 2s));
  EXPECT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, from).empty(); }, 1s));
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{0});
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  f.b.rig.run_for(2s);
  EXPECT_FALSE(f.turning());
}

// Found tripped at start with a set value, while a client writes its setpoint before the first
// whole cycle: the stop is owed all the same, so the fault clearing does not start the fan.
TEST(ModbusSetValueRuns, AFanFoundTrippedAtStartIsStoppedWhateverAClientWroteFirst) {
  Fan f;
  ASSERT_EQ(f.b.control("set set_value 1000").rfind("ok", 0), 0u);
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  const auto early = f.b.start_write({500}, kSetpointRegister);
  ASSERT_TRUE(f.b.until_online());
  ASSERT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, {}).empty(); }, 2s));
  EXPECT_EQ(f.written(kSetValue, {}), std::vector<std::uint16_t>{0});
  EXPECT_EQ(early->result, Outcome::ok);
  ASSERT_EQ(f.b.control("fault 0").rfind("ok", 0), 0u);
  f.b.rig.run_for(2s);
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 500u);
}

// Found at start with a set value and a speed it cannot read (sensor_fault, no trip): its set value
// commands it to run, so it is adopted running, never shown stopped over a turning fan, and no 0
// is written.
TEST(ModbusSetValueRuns, AFanFoundRunningWithASpeedNobodyCanReadIsAdopted) {
  Fan f;
  ASSERT_EQ(f.b.control("set set_value 800").rfind("ok", 0), 0u);
  ASSERT_EQ(f.b.control("set actual_speed 40000").rfind("ok", 0), 0u);  // beyond speed_rpm
  ASSERT_TRUE(f.b.until_online());
  f.b.rig.run_for(1s);
  EXPECT_EQ(f.b.read("command"), cmd::run_forward);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 800u);
  EXPECT_TRUE(f.written(kSetValue, {}).empty());
}

// A drive that refuses the owed stop for good (a locked rotor, the drive in local mode) is asked
// again backed off, up to the comm timeout apart, not at every cycle.
TEST(ModbusSetValueRuns, AStopTheDriveKeepsRefusingIsAskedAgainBackedOff) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.control("refuse holding 1 4 100000").rfind("ok", 0), 0u);
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  f.b.rig.run_for(20s);
  const std::size_t tries = f.written(kSetValue, from).size();
  EXPECT_GE(tries, 3u);
  EXPECT_LE(tries, 12u) << "asked at every cycle";
  EXPECT_EQ(f.b.read("command"), cmd::stop);
  EXPECT_EQ(f.b.status() & kCommLost, 0u) << "the fan's state still read";
}

// A reset with no run in force writes 0 to the set value before the reset bit: the error clears
// and the fan stays still until a client runs it again, at the setpoint it had.
TEST(ModbusSetValueRuns, AResetAfterATripNeverRestartsTheFan) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  ASSERT_EQ(f.b.control("fault 1").rfind("ok", 0), 0u);
  ASSERT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) != 0; }, 2s));
  ASSERT_TRUE(f.speed_is(0));
  f.b.rig.run_for(500ms);  // the driver's own stop is written
  const TimePoint from = f.b.rig.now();
  ASSERT_EQ(f.b.write({cmd::reset_fault}), Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{0});
  EXPECT_EQ(f.written(kReset, from), std::vector<std::uint16_t>{4});
  EXPECT_TRUE(f.b.rig.run_until([&] { return (f.b.status() & kFaulted) == 0; }, 2s));
  f.b.rig.run_for(2s);
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.read("speed_rpm"), 0u);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 1000u);
  ASSERT_EQ(f.b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_TRUE(f.speed_is(1000));
}

// "Stop, then acknowledge the fault": the reset does not overtake the stop, which is written.
TEST(ModbusSetValueRuns, AResetNeverOvertakesAStop) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  const auto stop = f.b.start_write({cmd::stop});
  const auto reset = f.b.start_write({cmd::reset_fault});
  ASSERT_TRUE(f.b.rig.run_until([&] { return stop->settled() && reset->settled(); }, 3s));
  EXPECT_EQ(stop->result, Outcome::ok);
  EXPECT_EQ(reset->result, Outcome::ok);
  EXPECT_TRUE(f.speed_is(0));
  EXPECT_FALSE(f.turning());
}

// A reset written while a run is on the line is decided when its turn comes: the run confirmed,
// there is a run in force and no 0 is written; the registers and the fan agree.
TEST(ModbusSetValueRuns, AResetBehindARunOnTheLineIsDecidedWhenItsTurnComes) {
  Fan f;
  ASSERT_TRUE(f.b.until_online());
  ASSERT_EQ(f.b.write({1000}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(f.b.control("late 40").rfind("ok", 0), 0u);
  const TimePoint from = f.b.rig.now();
  const auto run = f.b.start_write({cmd::run_forward});
  ASSERT_TRUE(f.b.rig.run_until([&] { return !f.written(kSetValue, from).empty(); }, 1s));
  const auto reset = f.b.start_write({cmd::reset_fault});
  ASSERT_TRUE(f.b.rig.run_until([&] { return run->settled() && reset->settled(); }, 3s));
  EXPECT_EQ(run->result, Outcome::ok);
  EXPECT_EQ(reset->result, Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), std::vector<std::uint16_t>{1000});
  f.b.rig.run_for(1s);
  EXPECT_EQ(f.b.read("command"), cmd::run_forward);
  EXPECT_TRUE(f.turning());
}

// A stop sent while a setpoint waits behind a run on the line: neither is lost to the other; the
// fan ends still, and the setpoint held is the newest.
TEST(ModbusSetValueRuns, AStopAndASetpointInQuickSuccessionEndStillWithTheNewestSetpoint) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  const auto set = f.b.start_write({700}, kSetpointRegister);
  const auto stop = f.b.start_write({cmd::stop});
  ASSERT_TRUE(f.b.rig.run_until([&] { return set->settled() && stop->settled(); }, 3s));
  EXPECT_EQ(set->result, Outcome::ok);
  EXPECT_EQ(stop->result, Outcome::ok);
  EXPECT_TRUE(f.speed_is(0));
  EXPECT_FALSE(f.turning());
  EXPECT_EQ(f.b.read("setpoint_rpm"), 700u);
  EXPECT_EQ(f.b.read("command"), cmd::stop);
}

// The stop is the drive's to refuse: refused, the run stays in force, and a setpoint sent after
// it goes to the drive, so the PLC reads the speed the motor turns at.
TEST(ModbusSetValueRuns, AStopTheDriveRefusesLeavesTheRunAndTheNextSetpointGoesToTheDrive) {
  Fan f;
  ASSERT_TRUE(f.running_at(1000));
  ASSERT_EQ(f.b.control("refuse holding 1 4 1").rfind("ok", 0), 0u);
  const TimePoint from = f.b.rig.now();
  const auto stop = f.b.start_write({cmd::stop});
  const auto set = f.b.start_write({600}, kSetpointRegister);
  ASSERT_TRUE(f.b.rig.run_until([&] { return set->settled() && stop->settled(); }, 3s));
  EXPECT_EQ(stop->result, Outcome::refused);
  EXPECT_EQ(set->result, Outcome::ok);
  EXPECT_EQ(f.written(kSetValue, from), (std::vector<std::uint16_t>{0, 600}));
  EXPECT_TRUE(f.speed_is(600));
  EXPECT_EQ(f.b.read("command"), cmd::run_forward);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 600u);
}

// A set value written 0 and up: a negative setpoint is refused (0x03), nothing sent.
TEST(ModbusSetValueRuns, ANegativeSetpointIsRefused) {
  Fan f;
  ASSERT_TRUE(f.b.until_online());
  const TimePoint from = f.b.rig.now();
  EXPECT_EQ(f.b.write({static_cast<std::uint16_t>(-500)}, kSetpointRegister),
            Outcome::invalid_value);
  EXPECT_EQ(f.b.read("setpoint_rpm"), 0u);
  EXPECT_TRUE(f.written(kSetValue, from).empty());
}

// A drive with a stop of its own beside a set value that runs it (a BLDC driver's brake register):
// stop writes that, not 0; the drive stays still while its set value still holds the last run's,
// a setpoint written meanwhile is held, and the next run writes the set value again.
TEST(ModbusSetValueRuns, AStopOfItsOwnIsWrittenAndTheNextRunWritesTheSetValueAgain) {
  std::string text(support::kFanProfile);
  text += "stop = { point = \"brake\", value = 0 }\n";
  text.insert(text.find("[common]"),
              "[[point]]\nname = \"brake\"\ntable = \"holding\"\naddress = 2\ntype = \"u16\"\n"
              "access = \"operate\"\n");
  support::ProfileFile file(text, "bldc.toml");
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.write({cmd::run_forward, 1000}), Outcome::ok);
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 1000u; }, 2s));
  const TimePoint from = b.rig.now();
  ASSERT_EQ(b.write({cmd::stop}), Outcome::ok);
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 0u; }, 2s));
  EXPECT_EQ(b.write({800}, kSetpointRegister), Outcome::ok);
  b.rig.run_for(1s);
  EXPECT_FALSE(b.sim_has("running"));
  const auto fc06 = [&](std::uint16_t address) { return written(b, address, from); };
  EXPECT_EQ(fc06(2), std::vector<std::uint16_t>{0});
  EXPECT_TRUE(fc06(kSetValue).empty());
  ASSERT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(fc06(kSetValue), std::vector<std::uint16_t>{800});
  EXPECT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 800u; }, 2s));
}

std::vector<std::string> errors_of(const std::string& common) {
  std::string text(support::kFanProfile);
  text = text.substr(0, text.find("[common]")) + common;
  auto parsed = parse_profile(text, "p.toml");
  if (std::holds_alternative<Profile>(parsed)) return {};
  return std::get<std::vector<std::string>>(parsed);
}

TEST(ModbusSetValueRuns, AProfileSaysNoOtherRunOrStopAndASetValueThatTakesZero) {
  const std::string runs = "[common]\nsetpoint_rpm = { point = \"set_value\", runs = true }\n";
  EXPECT_THAT(errors_of(runs + "run_forward = { point = \"reset\", value = 1 }\n"
                               "stop = { point = \"reset\", value = 0 }\n"),
              ElementsAre(HasSubstr("common.run_forward: goes not with common.setpoint_rpm.runs")));
  EXPECT_THAT(errors_of(runs + "unbound = { run_forward = \"none\" }\n"),
              ElementsAre(HasSubstr("common.run_forward: goes not with")));
  EXPECT_TRUE(errors_of(runs + "stop = { point = \"reset\", value = 0 }\n").empty());
  std::string text(support::kFanProfile);
  text.replace(text.find("min = 0"), 7, "min = 100");
  text = text.substr(0, text.find("[common]")) + runs;
  auto parsed = parse_profile(text, "p.toml");
  ASSERT_TRUE(std::holds_alternative<std::vector<std::string>>(parsed));
  EXPECT_THAT(std::get<std::vector<std::string>>(parsed),
              ElementsAre(HasSubstr("'set_value' must take 0 (its min..max)")));
  text = support::kFanProfile;
  text.replace(text.find("type = \"u16\"\nmin = 0"), 12, "type = \"u32\"");
  text = text.substr(0, text.find("[common]")) + runs;
  parsed = parse_profile(text, "p.toml");
  ASSERT_TRUE(std::holds_alternative<std::vector<std::string>>(parsed));
  EXPECT_THAT(std::get<std::vector<std::string>>(parsed),
              ElementsAre(HasSubstr("'set_value' must be one register")));
  EXPECT_TRUE(errors_of(runs).empty());
}

}  // namespace
}  // namespace drivegate::modbus_device
