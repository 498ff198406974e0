// The driver against its simulator on the real bus engine: the poll plan, the keep-alive, faults,
// resends, comm_lost and recovery, asserted on the frames on the wire (with their times where
// timing matters) and on the registers a PLC reads.
#include "driver.h"

#include <gtest/gtest.h>

#include "bench.h"
#include "faults.h"
#include "late_reply_contract.h"

namespace drivegate::mdriver {
namespace {

using test::LateReplyContract;

// Late replies (late_reply_contract.h): the 200 ms reply timeout, answered 260 ms late.
const test::LateReplyFacts kLate{.id = "mdriver-2400", .late = 260ms};
INSTANTIATE_TEST_SUITE_P(Mdriver2400, LateReplyContract, testing::Values(kLate));

TEST(MdriverDriverFromPowerOn, StartsWithTheFixedCodeCheckThenPollsWithTheStopCode) {
  Bench b;
  EXPECT_EQ(b.read("status") & kOnline, 0u);
  ASSERT_TRUE(b.ready());
  const auto& sent = b.rig.sent();
  ASSERT_GE(sent.size(), 2u);
  EXPECT_EQ(sent[0].bytes, kCheck);
  EXPECT_EQ(sent[1].bytes, kRunStop);
  // The first run command follows the check's answer at once, after the 10 ms gap: the check
  // (9 bytes) out, the driver's turnaround, its echo (9 bytes) back.
  EXPECT_EQ(sent[1].at - sent[0].at,
            b.on_wire(9) + b.rig.line().turnaround + b.on_wire(9) + kInterFrameGap);
  EXPECT_EQ(b.read("status") & (kOnline | kRunning | kFaulted), kOnline);
  EXPECT_EQ(b.read("fixed_code_state"), 1u);
  EXPECT_EQ(b.read("ipm_temperature"), 26u);  // the simulator's default, the document's [1a]
  EXPECT_EQ(b.read("target_code"), 0x01u);
  EXPECT_EQ(b.read("sent_code"), 0x01u);
  EXPECT_EQ(b.read("fault_code"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST(MdriverDriverFromPowerOn, ChecksUntilAnsweredThenPolls) {
  Bench b;
  b.control("silent on");
  b.rig.run_for(3s);
  const auto silent = b.frames();
  EXPECT_GE(silent.size(), 6u);
  for (const auto& f : silent) EXPECT_EQ(f, kCheck);  // nothing but the check, identical
  EXPECT_EQ(b.read("status") & kOnline, 0u);
  EXPECT_EQ(b.read("fixed_code_state"), 0u);  // unchecked
  b.control("silent off");
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 10s));
  b.rig.run_for(200ms);
  EXPECT_EQ(b.last(), kRunStop);
}

TEST(MdriverDriverFromPowerOn, TheRunCommandIsTheKeepAliveAtTheShorterOfPollAndKeepAlive) {
  const auto spacing = [](const Bench& b, TimePoint from) {
    const auto t = b.times_of(kRunStop, from);
    std::vector<Millis> out;
    for (std::size_t i = 1; i < t.size(); ++i) {
      out.push_back(std::chrono::duration_cast<Millis>(t[i] - t[i - 1]));
    }
    return out;
  };
  Bench slow({.options = {{"keepalive_ms", "1000"}}, .poll = 5000ms});  // the keep-alive rules
  ASSERT_TRUE(slow.ready());
  TimePoint from = slow.rig.now();
  slow.rig.run_for(10s);
  EXPECT_EQ(slow.frames(from).size(), 10u);
  for (const Millis gap : spacing(slow, from)) EXPECT_EQ(gap, 1000ms);

  Bench fast({.options = {{"keepalive_ms", "1000"}}, .poll = 250ms});  // the poll rules
  ASSERT_TRUE(fast.ready());
  from = fast.rig.now();
  fast.rig.run_for(10s);
  EXPECT_EQ(fast.frames(from).size(), 40u);
  for (const Millis gap : spacing(fast, from)) EXPECT_EQ(gap, 250ms);

  // A gateway polled once a minute still never lets the driver trip with 0x0C (after 6 s).
  Bench idle({.options = {{"keepalive_ms", "5000"}}, .poll = 60000ms});
  ASSERT_TRUE(idle.ready());
  from = idle.rig.now();
  idle.rig.run_for(60s);
  for (const Millis gap : spacing(idle, from)) EXPECT_EQ(gap, 5000ms);
  EXPECT_EQ(idle.read("fault_code"), 0u);
  EXPECT_EQ(idle.read("error_code"), 0u);
  EXPECT_TRUE(idle.sim_has("error=0x00"));
}

using MdriverDriver = test::ReadyBench<Bench>;

TEST_F(MdriverDriver, EveryErrorCodeMapsIntoFaultsAndNativeFault) {
  for (const auto& e : error_codes()) {
    SCOPED_TRACE(std::string(e.name));
    b.control("fault " + std::to_string(e.code));
    b.rig.run_for(600ms);  // at least one keep-alive reply
    EXPECT_EQ(b.read("fault_mask"), 1u << static_cast<unsigned>(e.fault));
    EXPECT_EQ(b.read("native_fault"), e.code);
    EXPECT_EQ(b.read("error_code"), e.code);
    EXPECT_NE(b.read("status") & kFaulted, 0u);
    EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::ok);
    EXPECT_EQ(b.read("fault_mask"), 0u);
    EXPECT_EQ(b.read("native_fault"), 0u);
  }
}

TEST_F(MdriverDriver, OverTemperatureTripsAndResetFaultClearsIt) {
  ASSERT_TRUE(b.running_at_1149());
  b.rig.run_for(2s);
  b.control("fault ipm_over_temperature");
  b.rig.run_for(1s);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::drive_over_temperature));
  EXPECT_EQ(b.read("native_fault"), 0x0Eu);
  EXPECT_EQ(b.read("error_code"), 0x0Eu);
  EXPECT_EQ(b.read("status") & (kRunning | kFaulted), kFaulted);
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  // Latched: a run command would not run. Refused at once, without a frame.
  const auto before = b.rig.sent().size();
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::refused);
  EXPECT_EQ(b.rig.sent().size(), before);

  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0), kRunReset);
  EXPECT_EQ(b.read("fault_code"), 0u);
  EXPECT_EQ(b.read("native_fault"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);  // [00] resets and stops
  b.rig.run_for(1s);
  EXPECT_EQ(b.last(), kRunStop);  // reset once, then the plain stop code
  EXPECT_EQ(b.count(kRunReset), 1u);
  const TimePoint again = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.frames(again).at(0), kRun1149);
}

TEST(MdriverDriverFromPowerOn, AFailedFixedCodeCheckIsAHardwareFaultAndNotReady) {
  Bench b;
  b.control("eeprom fail");
  b.rig.run_for(3s);
  EXPECT_EQ(b.read("status") & (kOnline | kFaulted), kFaulted);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::hardware_fault));
  EXPECT_EQ(b.read("native_fault"), kNativeFixedCodeError);
  EXPECT_EQ(b.read("fixed_code_state"), 2u);
  for (const auto& f : b.frames()) EXPECT_EQ(f, kCheck);  // no run data while the code fails
  // It answers, so not 0x0B: a driver that is not ready refuses.
  EXPECT_EQ(b.write({cmd::stop}), Outcome::refused);
  b.control("eeprom ok");
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 3s));
  b.rig.run_for(200ms);
  EXPECT_EQ(b.read("fault_code"), 0u);
  EXPECT_EQ(b.read("fixed_code_state"), 1u);
  EXPECT_EQ(b.last(), kRunStop);
}

TEST_F(MdriverDriver, ABadChecksumIsResentIdenticallyAtOnce) {
  ASSERT_EQ(b.write({1149}, kSetpointRegister), Outcome::ok);
  b.control("corrupt 1");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  const auto runs = b.times_of(kRun1149, asked);
  ASSERT_EQ(runs.size(), 2u);
  // The damaged reply is complete (13 bytes) before the same frame goes again, after the gap.
  EXPECT_EQ(runs[1] - runs[0],
            b.on_wire(8) + b.rig.line().turnaround + b.on_wire(13) + kInterFrameGap);
  EXPECT_EQ(b.read("bad_checksum"), 1u);
  EXPECT_EQ(b.read("retries"), 1u);
  EXPECT_EQ(b.read("timeouts"), 0u);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

TEST_F(MdriverDriver, SilenceIsResentThreeTimesThenCommLostRedoesTheCheck) {
  ASSERT_TRUE(b.running_at_1149());
  b.control("silent on");
  const TimePoint from = b.rig.now();
  b.rig.run_for(1s);
  // One turn: identical keep-alives, each after the 200 ms reply timeout counted from the end of
  // the frame on the wire (8 bytes, counted in whole ms) and the engine's guard time after it;
  // of the three attempts, the two the default 1000 ms budget holds.
  const auto tries = b.times_of(kRun1149, from);
  ASSERT_GE(tries.size(), 2u);
  const Millis per_attempt =
      unanswered_attempt(kReplyTimeout) + std::chrono::duration_cast<Millis>(b.on_wire(8));
  EXPECT_EQ(tries[1] - tries[0], per_attempt);
  ASSERT_TRUE(b.rig.run_until([&] { return (b.read("status") & kCommLost) != 0; }, 7s));
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::comm_lost));
  EXPECT_EQ(b.read("fixed_code_state"), 0u);  // the handshake is forgotten
  ASSERT_TRUE(b.rig.run_until([&] { return b.last() == kCheck; }, 6s));
  b.control("silent off");
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 6s));
  b.rig.run_for(200ms);
  EXPECT_EQ(b.read("status") & kCommLost, 0u);
  // The run in force survives comm_lost: the keep-alive carries it again.
  EXPECT_EQ(b.last(), kRun1149);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.read("setpoint_rpm"), 1149u);
}

TEST_F(MdriverDriver, APowerCycledDriverIsCheckedAgain) {
  b.control("power-cycle");  // forgets the check: ignores run data until checked again
  ASSERT_TRUE(b.rig.run_until([&] { return b.count(kCheck) == 2 && b.drive->online(); }, 15s));
  b.rig.run_for(1s);
  EXPECT_EQ(b.count(kCheck), 2u);
  EXPECT_EQ(b.last(), kRunStop);
  EXPECT_TRUE(b.sim_has("checked=1"));
}

TEST(MdriverDriverFromPowerOn, NoiseAndOtherDriversFramesAreSkipped) {
  Bench b;
  // Before every answer: three bytes of garbage and another driver's echo (address 02).
  Bytes junk{0xFF, 0xFF, 0x33};
  const Bytes other = encode_check_reply(0x02, 0x00, kFixedCode);
  junk.insert(junk.end(), other.begin(), other.end());
  b.rig.line().device_filter = [junk](Bytes answer) {
    answer.insert(answer.begin(), junk.begin(), junk.end());
    return answer;
  };
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.write({cmd::run_forward, 1149}), Outcome::ok);
  EXPECT_GE(b.read("foreign_frames"), 2u);
  EXPECT_EQ(b.read("bad_checksum"), 0u);  // the garbage is noise, not a damaged reply
  EXPECT_EQ(b.read("retries"), 0u);
  EXPECT_EQ(b.read("timeouts"), 0u);
}

TEST(MdriverDriverFromPowerOn, AddressesAreConfigurable) {
  Bench b({.options = {{"master_address", "16"}}, .address = 0x22});
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.frames().at(0), (Bytes{0x10, 0x22, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x07}));
  EXPECT_EQ(b.frames().at(1), (Bytes{0x10, 0x22, 0x10, 0x02, 0x01, 0x01, 0x00, 0x0F}));

  // The factories refuse a master address equal to the device's, and two-byte addresses.
  DeviceEnv env;
  env.address = 0x10;
  env.options = test::options_of(drivegate_adapter, {{"master_address", "16"}});
  std::string error;
  EXPECT_EQ(drivegate_adapter.create_driver(env, error), nullptr);
  EXPECT_NE(error.find("master_address"), std::string::npos);
  env.address = 0x100;
  error.clear();
  EXPECT_EQ(drivegate_adapter.create_driver(env, error), nullptr);
  EXPECT_NE(error.find("address"), std::string::npos);
  SimEnv sim_env;
  sim_env.address = 0x10;
  sim_env.options = env.options;
  error.clear();
  EXPECT_EQ(drivegate_adapter.create_simulator(sim_env, error), nullptr);
  EXPECT_FALSE(error.empty());
}

}  // namespace
}  // namespace drivegate::mdriver
