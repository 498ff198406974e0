// The driver against its simulator on the real bus engine: the poll plan with its exact frames
// and times, the points a PLC reads, resends, replies that are not the awaited one, comm_lost and
// recovery, and the float byte order option.
#include <gtest/gtest.h>

#include "bench.h"
#include "late_reply_contract.h"
#include "points.h"

namespace drivegate::unicla {
namespace {

using test::LateReplyContract;

// Late replies (late_reply_contract.h): reply_timeout_ms 100 (the default), answered 130 ms late;
// the sequence numbers alone would not catch a reply that comes in the next read's window with the
// next number.
const test::LateReplyFacts kLate{.id = "unicla-edrive", .late = 130ms};
INSTANTIATE_TEST_SUITE_P(UniclaEdrive, LateReplyContract, testing::Values(kLate));

// README.md, "Frames": the driver's start-up reads and first poll, device 1.
const Bytes kBuildRead1 = {0x7E, 0x00, 0x01, 0xC0, 0x02, 0x01, 0x00, 0x00, 0x00, 0x34, 0x66, 0x7E};
const Bytes kLimitsRead2 = {0x7E, 0x00, 0x01, 0xC0, 0x03, 0x02, 0x00, 0x00, 0x00, 0x05, 0xEB, 0x7E};
const Bytes kStatusRead3 = {0x7E, 0x00, 0x01, 0xC0, 0x01, 0x03, 0x00, 0x00, 0x00, 0x37, 0xDC, 0x7E};

using UniclaDriver = test::ReadyBench<Bench>;

TEST_F(UniclaDriver, StartUpReadsBuildThenLimitsThenPollsStatus) {
  const auto sent = b.sent();
  ASSERT_GE(sent.size(), 3u);
  // Sequence numbers from 1; each read as soon as the one before was answered, after the gap.
  EXPECT_EQ(sent[0].bytes, kBuildRead1);
  EXPECT_EQ(sent[1].bytes, kLimitsRead2);
  EXPECT_EQ(sent[2].bytes, kStatusRead3);
  const auto& answers = b.rig.answers();
  ASSERT_GE(answers.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const TimePoint answered = answers[i].at + b.on_wire(answers[i].bytes.size());
    EXPECT_EQ(sent[i + 1].at, answered + kInterFrameGap) << i;
  }
  EXPECT_NE(b.read("status") & kOnline, 0u);
  EXPECT_EQ(b.read_text("model"), "EDRIVE-SIM-24V");
  EXPECT_EQ(b.read_text("serial_number"), "SIM1000001");
  EXPECT_EQ(b.read_text("device_name"), "drivegate simulated eDrive 1");
  EXPECT_EQ(b.read("refrigerant"), 2u);  // R1234YF
  EXPECT_EQ(b.read("oil"), 5u);          // POE68
  EXPECT_EQ(b.read("build_min_speed"), 1000u);
  EXPECT_EQ(b.read("build_max_speed"), 6500u);
  EXPECT_EQ(b.read("limit_min_speed"), 1500u);
  EXPECT_EQ(b.read("limit_max_speed"), 6000u);
  EXPECT_EQ(b.read("control_enabled"), 1u);
  EXPECT_EQ(b.read("rs485_device_id"), 1u);
  EXPECT_FLOAT_EQ(b.read_f32("discharge_pressure_high"), 28.0F);
  // The simulated drive at rest: equalised pressures, stopped.
  EXPECT_FLOAT_EQ(b.read_f32("suction_pressure"), 4.5F);
  EXPECT_FLOAT_EQ(b.read_f32("discharge_pressure"), 6.5F);
  EXPECT_EQ(b.read("op_state"), kStopped);
  EXPECT_EQ(b.read("control_mode"), 4u);  // External Serial
  EXPECT_EQ(b.read("status") & kRunning, 0u);
  // Nothing was written: nothing is in force but stop.
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
}

TEST_F(UniclaDriver, PollsStatusAtThePollInterval) {
  const TimePoint from = b.rig.now();
  b.rig.run_for(5s);
  const auto polls = b.sent(from);
  ASSERT_EQ(polls.size(), 10u);  // nothing but status reads, every 500 ms
  for (std::size_t i = 0; i < polls.size(); ++i) {
    const Frame& f = polls[i].frame;
    EXPECT_EQ(f.message_id, kStatus);
    EXPECT_EQ(f.command, kRead);
    EXPECT_EQ(f.destination, 0x01);
    EXPECT_TRUE(f.payload.empty());  // "Read: payload 0"
    if (i == 0) continue;
    EXPECT_EQ(polls[i].at - polls[i - 1].at, 500ms) << i;
    EXPECT_EQ(f.sequence, static_cast<std::uint8_t>(polls[i - 1].frame.sequence + 1));
  }
  EXPECT_EQ(b.read("timeouts"), 0u);
  EXPECT_EQ(b.read("retries"), 0u);
}

TEST(UniclaDriverFromPowerOn, PollIntervalIsTheDevicesOwn) {
  Bench b({.poll = 200ms});
  ASSERT_TRUE(b.ready());
  const TimePoint from = b.rig.now();
  b.rig.run_for(1s);
  const auto polls = b.sent(from, kStatus);
  ASSERT_EQ(polls.size(), 5u);
  for (std::size_t i = 1; i < polls.size(); ++i) EXPECT_EQ(polls[i].at - polls[i - 1].at, 200ms);
}

TEST(UniclaDriverFromPowerOn, PointsCarryTypesUnitsAndLabels) {
  Bench b;
  const auto& p = b.drive->driver().points();
  ASSERT_EQ(p.size(), pt::count);
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_FALSE(p[i].name.empty()) << i;  // every index has its point
    EXPECT_EQ(p[i].access(), Access::read) << p[i].name;
  }
  EXPECT_EQ(p[pt::suction_pressure].name, "suction_pressure");
  EXPECT_EQ(p[pt::suction_pressure].type, PointType::f32);
  EXPECT_EQ(p[pt::suction_pressure].unit, "bar");
  EXPECT_EQ(p[pt::suction_temperature].unit, "degC");
  EXPECT_EQ(p[pt::suction_superheat].unit, "K");
  EXPECT_EQ(p[pt::compressor_rpm].unit, "rpm");
  EXPECT_EQ(p[pt::model].type, PointType::string);
  EXPECT_EQ(p[pt::model].string_registers, 8);
  EXPECT_EQ(p[pt::serial_number].string_registers, 8);
  EXPECT_EQ(p[pt::device_name].string_registers, 16);
  EXPECT_EQ(p[pt::op_state].labels.size(), 17u);
  EXPECT_EQ(p[pt::op_state].labels[7].name, "Fault - Motor");
  EXPECT_EQ(p[pt::op_state].labels[7].value, 7u);
  EXPECT_EQ(p[pt::refrigerant].labels[2].name, "R1234YF");
  EXPECT_EQ(p[pt::oil].labels[5].name, "POE68");
  EXPECT_EQ(p[pt::control_mode].labels[4].name, "External Serial");
  EXPECT_TRUE(p[pt::motor_safety_run].bit_labels);
  EXPECT_EQ(p[pt::motor_safety_run].labels.size(), 15u);  // bit 0 is "X"
  EXPECT_EQ(p[pt::motor_safety_run].labels.front().value, 1u);
  EXPECT_EQ(p[pt::motor_safety_run].labels.back().name, "ST Motor Control - Software Error");
  EXPECT_EQ(p[pt::compressor_safety_start].labels.size(), 12u);  // bits 0..3 are "X"
  EXPECT_EQ(p[pt::compressor_safety_start].labels.front().value, 4u);
  EXPECT_EQ(p[pt::electrical_safety].type, PointType::u32);
  EXPECT_EQ(p[pt::electrical_safety].labels.size(), 19u);     // 24 bits minus five "X"
  EXPECT_EQ(p[pt::electrical_safety].labels[11].value, 16u);  // CMC 3V3 Fault
  EXPECT_EQ(p[pt::control_enabled].labels.size(), 2u);
  // The register map lays them out after the common block, in this order (the e2e test and the
  // printed register map rely on it): suction_pressure at input 32, model at 63.
  EXPECT_EQ(b.drive->map().find("suction_pressure")->address, 32);
  EXPECT_EQ(b.drive->map().find("model")->address, 63);
}

TEST_F(UniclaDriver, ABadCrcIsResentIdenticallyAfterTheGap) {
  b.control("corrupt 1");
  const TimePoint from = b.rig.now();
  const std::size_t answered = b.rig.answers().size();
  b.rig.run_for(600ms);
  const auto sent = b.sent(from);
  ASSERT_GE(sent.size(), 2u);
  EXPECT_EQ(sent[0].bytes, sent[1].bytes);  // the same frame, the same sequence
  // At once: the gap after the damaged reply ended, not after the reply timeout.
  const auto& damaged = b.rig.answers().at(answered);
  EXPECT_EQ(sent[1].at, damaged.at + b.on_wire(damaged.bytes.size()) + kInterFrameGap);
  EXPECT_EQ(b.read("bad_checksum"), 1u);
  EXPECT_EQ(b.read("retries"), 1u);
  EXPECT_EQ(b.read("timeouts"), 0u);
  EXPECT_NE(b.read("status") & kOnline, 0u);
}

// A compressor found running (the gateway restarted, or this device was changed by a
// reload) is shown as it runs, a run in force at its speed; nothing is sent to it, and a new
// speed goes out as a speed change of a running compressor.
TEST(UniclaDriverFromPowerOn, ACompressorFoundRunningIsShownAsItRunsNeverAsStopped) {
  Bench b;
  ASSERT_EQ(b.control("run 3000").rfind("ok", 0), 0u);
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  EXPECT_EQ(b.read("setpoint_rpm"), 3000u);
  EXPECT_NE(b.status() & kRunning, 0u);
  EXPECT_TRUE(b.sent({}, kRunState).empty());  // nothing was sent to it
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({3500}, kSetpointRegister), Outcome::ok);
  const auto runs = b.sent(asked, kRunState);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].frame.payload, (Bytes{0x0D, 0xAC}));  // 3500 rpm
  EXPECT_TRUE(b.sim_has("target=3500"));
}

TEST_F(UniclaDriver, ASilentReadIsTriedThreeTimesEachAfterTheReplyTimeout) {
  b.control("silent on");
  const TimePoint from = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("timeouts") == 3; }, 1s));
  EXPECT_EQ(b.read("retries"), 2u);
  b.rig.run_for(500ms);
  const auto sent = b.sent(from);
  ASSERT_GE(sent.size(), 4u);
  EXPECT_EQ(sent[0].bytes, sent[1].bytes);
  EXPECT_EQ(sent[1].bytes, sent[2].bytes);
  // reply_timeout_ms (100) from the end of the 12-byte frame (6.25 ms, counted as 6), then the
  // engine's guard time (the timeout again).
  EXPECT_EQ(sent[1].at - sent[0].at, 206ms);
  EXPECT_EQ(sent[2].at - sent[1].at, 206ms);
  // Then the next poll, a new frame, overdue at the poll interval: once the last attempt's guard
  // has passed.
  EXPECT_NE(sent[3].bytes, sent[2].bytes);
  EXPECT_EQ(sent[3].frame.sequence, static_cast<std::uint8_t>(sent[0].frame.sequence + 1));
  EXPECT_EQ(sent[3].at - sent[0].at, 3 * 206ms);
}

TEST(UniclaDriverFromPowerOn, RetriesAndReplyTimeoutFollowTheOptions) {
  Bench b({.options = {{"retries", "0"}, {"reply_timeout_ms", "250"}}});
  ASSERT_TRUE(b.ready());
  b.control("silent on");
  const TimePoint from = b.rig.now();
  b.rig.run_for(1s);
  const auto sent = b.sent(from);
  ASSERT_GE(sent.size(), 2u);
  // One attempt a turn: the next poll is a new frame (new sequence), at the poll interval, or
  // once the attempt's 250 ms timeout and guard time have passed (6 + 2 x 250 ms).
  EXPECT_NE(sent[0].bytes, sent[1].bytes);
  EXPECT_EQ(sent[1].frame.sequence, static_cast<std::uint8_t>(sent[0].frame.sequence + 1));
  EXPECT_EQ(sent[1].at - sent[0].at, 506ms);
  EXPECT_EQ(b.read("retries"), 0u);
}

// Good frames that are not the awaited reply: a reply to an earlier sequence, another drive's,
// one for another master address. Each is counted foreign, the read is resent, and the real
// reply is taken.
TEST_F(UniclaDriver, RepliesThatAreNotTheAwaitedOneAreForeign) {
  int changed = 0;
  b.rig.line().device_filter = [&changed](Bytes bytes) {
    Frame f = decoded(bytes);
    if (f.message_id != kStatus || changed >= 3) return bytes;
    switch (changed++) {
      case 0:
        f.sequence = static_cast<std::uint8_t>(f.sequence - 1);  // a late reply
        break;
      case 1:
        f.source = 0x02;  // another drive
        break;
      default:
        f.destination = 0x05;  // not for the master
        break;
    }
    return encode(f);
  };
  const TimePoint from = b.rig.now();
  b.rig.run_for(2s);
  EXPECT_EQ(b.read("foreign_frames"), 3u);
  EXPECT_EQ(b.read("timeouts"), 3u);  // each attempt waited out its timeout
  const auto sent = b.sent(from, kStatus);
  ASSERT_GE(sent.size(), 4u);
  EXPECT_EQ(sent[0].bytes, sent[1].bytes);
  EXPECT_EQ(sent[1].bytes, sent[2].bytes);
  EXPECT_NE(b.read("status") & kOnline, 0u);
  EXPECT_EQ(b.read("bad_checksum"), 0u);
}

// A checked frame whose payload is shorter than a status: not the reply, and not counted good.
TEST_F(UniclaDriver, AShortStatusPayloadIsNotAReply) {
  bool once = true;
  b.rig.line().device_filter = [&once](Bytes bytes) {
    Frame f = decoded(bytes);
    if (!once || f.message_id != kStatus) return bytes;
    once = false;
    f.payload.resize(kStatusSize - 1);
    return encode(f);
  };
  const std::uint32_t good = b.read("frames_good");
  b.rig.run_for(800ms);
  EXPECT_EQ(b.read("timeouts"), 1u);
  EXPECT_EQ(b.read("retries"), 1u);
  EXPECT_EQ(b.read("foreign_frames"), 0u);
  EXPECT_EQ(b.read("frames_good"), good + 1);  // only the resent read's reply
}

TEST_F(UniclaDriver, CommLostRedoesStartUpAndComesBack) {
  b.control("silent on");
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->comm_lost(); }, 10s));
  // No good frame for comm_timeout: max(3 s, 4 x 500 ms + 3 x 100 ms).
  EXPECT_EQ(b.drive->driver().traits().comm_timeout, 3000ms);
  EXPECT_EQ(b.read("status") & (kOnline | kCommLost), kCommLost);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::comm_lost));
  // From then on the drive is probed with the start-up read, backed off.
  b.rig.run_for(100ms);
  const TimePoint from = b.rig.now();
  b.rig.run_for(3s);
  const auto probes = b.sent(from);
  ASSERT_FALSE(probes.empty());
  for (const auto& p : probes) EXPECT_EQ(p.frame.message_id, kBuild);
  b.control("silent off");
  const TimePoint back = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 10s));
  const auto reads = b.sent(back);
  ASSERT_GE(reads.size(), 3u);
  EXPECT_EQ(reads[reads.size() - 3].frame.message_id, kBuild);
  EXPECT_EQ(reads[reads.size() - 2].frame.message_id, kLimits);
  EXPECT_EQ(reads[reads.size() - 1].frame.message_id, kStatus);
  EXPECT_EQ(b.read("status") & kCommLost, 0u);
  EXPECT_EQ(b.read("fault_code"), 0u);
}

TEST(UniclaDriverFromPowerOn, LittleEndianFloatsFollowTheOption) {
  Bench b({.options = {{"byte_order", "little"}}, .address = 3});
  ASSERT_TRUE(b.ready());
  EXPECT_FLOAT_EQ(b.read_f32("suction_pressure"), 4.5F);
  EXPECT_FLOAT_EQ(b.read_f32("discharge_pressure_high"), 28.0F);
  EXPECT_EQ(b.read("limit_max_speed"), 6000u);
  EXPECT_EQ(b.read("rs485_device_id"), 3u);

  // A drive sending its floats the other way than configured: integers still hold.
  Bench mismatched({.sim_options = test::OptionText{{"byte_order", "little"}}, .address = 3});
  ASSERT_TRUE(mismatched.ready());
  EXPECT_NE(mismatched.read_f32("suction_pressure"), 4.5F);
  EXPECT_EQ(mismatched.read("limit_max_speed"), 6000u);
}

TEST_F(UniclaDriver, FaultsAndWarningsAsAPlcReadsThem) {
  b.control("fault overvoltage");
  b.rig.run_for(600ms);
  EXPECT_NE(b.read("status") & kFaulted, 0u);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::over_voltage));
  EXPECT_EQ(b.read("native_fault"), kFaultMotor);
  EXPECT_EQ(b.read("motor_safety_run"), 1u << 9);
  b.control("clear");
  b.control("flags compressor_start 0x0800");  // Low Side Pressure Low, no Fault-* state
  b.rig.run_for(600ms);
  EXPECT_EQ(b.read("status") & kFaulted, 0u);
  EXPECT_NE(b.read("status") & kWarning, 0u);
  EXPECT_EQ(b.read("native_fault"), 0u);
  EXPECT_EQ(b.read("compressor_safety_start"), 0x0800u);
}

}  // namespace
}  // namespace drivegate::unicla
