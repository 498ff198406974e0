// The driver against the simulator on a simulated line: exact frames, poll plan, retries,
// write confirmation through status reads, fault mapping and comm_lost recovery.
#include "driver.h"

#include <gtest/gtest.h>

#include "faults.h"
#include "harness.h"
#include "points.h"

namespace drivegate::unicla {
namespace {

using test_support::Rig;
using test_support::sent_frame;

constexpr std::uint8_t kStatus = 0x01, kBuild = 0x02, kLimits = 0x03, kRun = 0xC0, kAck = 0xC1;

std::int64_t as_int(const Value& v) {
  return std::get<std::int64_t>(v);
}

TEST(UniclaDriver, StartUpReadsBuildThenLimitsThenPollsStatus) {
  Rig r;
  r.start();
  ASSERT_GE(r.bus.sent.size(), 3u);
  // Sequence numbers start at 1; CRCs per "Cyclic Redundancy Check" (see codec_test).
  EXPECT_EQ(r.bus.sent[0],
            (Bytes{0x7E, 0x00, 0x01, 0xC0, 0x02, 0x01, 0x00, 0x00, 0x00, 0x34, 0x66, 0x7E}));
  EXPECT_EQ(r.bus.sent[1],
            (Bytes{0x7E, 0x00, 0x01, 0xC0, 0x03, 0x02, 0x00, 0x00, 0x00, 0x05, 0xEB, 0x7E}));
  EXPECT_EQ(r.bus.sent[2],
            (Bytes{0x7E, 0x00, 0x01, 0xC0, 0x01, 0x03, 0x00, 0x00, 0x00, 0x37, 0xDC, 0x7E}));
  EXPECT_TRUE(r.driver.common().ready);
  const auto& v = r.driver.values();
  EXPECT_EQ(std::get<std::string>(v[kModel]), "EDRIVE-SIM-24V");
  EXPECT_EQ(std::get<std::string>(v[kSerialNumber]), "SIM1000001");
  EXPECT_EQ(std::get<std::string>(v[kDeviceName]), "drivegate simulated eDrive 1");
  EXPECT_EQ(as_int(v[kRefrigerant]), 2);
  EXPECT_EQ(as_int(v[kOil]), 5);
  EXPECT_EQ(as_int(v[kLimitMinSpeed]), 1500);
  EXPECT_EQ(as_int(v[kLimitMaxSpeed]), 6000);
  EXPECT_EQ(as_int(v[kControlEnabled]), 1);
  EXPECT_DOUBLE_EQ(std::get<double>(v[kSuctionPressure]), 4.5);
  EXPECT_DOUBLE_EQ(std::get<double>(v[kDischargePressure]), 6.5);
  EXPECT_EQ(as_int(v[kOpState]), 3);  // Stopped
  EXPECT_EQ(v.size(), r.driver.points().size());
}

TEST(UniclaDriver, PollsStatusAtThePollInterval) {
  Rig r;
  r.start();
  const std::size_t from = r.bus.sent.size();
  r.bus.run_for(Millis(5000));
  const auto polls = r.sent_with(kStatus, from);
  EXPECT_GE(polls.size(), 9u);
  EXPECT_LE(polls.size(), 11u);
  EXPECT_EQ(r.sent_with(kBuild, from).size(), 0u);  // build / limits only at start-up
  for (std::size_t i = 1; i < polls.size(); ++i) {
    EXPECT_EQ(polls[i].sequence, static_cast<std::uint8_t>(polls[i - 1].sequence + 1));
    EXPECT_EQ(polls[i].command, 0xC0);
    EXPECT_TRUE(polls[i].payload.empty());
  }
}

TEST(UniclaDriver, PointsCarryTypesUnitsAndLabels) {
  Rig r;
  const auto& p = r.driver.points();
  ASSERT_EQ(p.size(), kPointCount);
  EXPECT_EQ(p[kSuctionPressure].type, PointType::f32);
  EXPECT_EQ(p[kSuctionPressure].unit, "bar");
  EXPECT_EQ(p[kSuctionTemperature].unit, "degC");
  EXPECT_EQ(p[kSuctionSuperheat].unit, "K");
  EXPECT_EQ(p[kModel].type, PointType::string);
  EXPECT_EQ(p[kModel].string_registers, 8);
  EXPECT_EQ(p[kDeviceName].string_registers, 16);
  EXPECT_EQ(p[kOpState].labels.size(), 17u);
  EXPECT_EQ(p[kOpState].labels[7].name, "Fault - Motor");
  EXPECT_EQ(p[kMotorRunFlags].labels.back().name, "ST Motor Control - Software Error");
  EXPECT_TRUE(p[kMotorRunFlags].bit_labels);
  EXPECT_EQ(p[kElectricalFlags].type, PointType::u32);
  EXPECT_EQ(p[kElectricalFlags].labels.size(), 19u);  // 24 bits minus five "X"
  for (const PointSpec& s : p) EXPECT_EQ(s.access(), Access::read) << s.name;
}

TEST(UniclaDriver, RunAt3000ConfirmedByStatusThenStop) {
  Rig r;
  r.start();
  EXPECT_EQ(r.driver.setpoint(3000, 1, r.now()), WriteStatus::done);  // stored while stopped
  EXPECT_EQ(r.driver.common().setpoint_rpm, 3000);
  const std::size_t from = r.bus.sent.size();
  ASSERT_EQ(r.driver.command(Command::run_forward, 2, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(2), WriteResult::ok);
  const auto runs = r.sent_with(kRun, from);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].command, 0xC1);
  EXPECT_EQ(runs[0].destination, 0x01);
  EXPECT_EQ(runs[0].payload, (Bytes{0x0B, 0xB8}));  // 3000 rpm
  // The write goes out first, the confirming status read right after it.
  EXPECT_EQ(sent_frame(r.bus.sent[from]).message_id, kRun);
  EXPECT_EQ(sent_frame(r.bus.sent[from + 1]).message_id, kStatus);
  EXPECT_EQ(r.driver.common().command, Command::run_forward);
  r.bus.run_for(Millis(4000));
  EXPECT_EQ(r.driver.common().speed_rpm, 3000);
  EXPECT_TRUE(r.driver.common().running);
  EXPECT_EQ(as_int(r.driver.values()[kOpState]), 2);  // Running
  EXPECT_LT(std::get<double>(r.driver.values()[kSuctionPressure]), 4.5);

  const std::size_t stop_from = r.bus.sent.size();
  ASSERT_EQ(r.driver.command(Command::stop, 3, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(3), WriteResult::ok);
  const auto stops = r.sent_with(kRun, stop_from);
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_EQ(stops[0].payload, (Bytes{0x00, 0x00}));  // "a value of 0 is treated as a stop"
  r.bus.run_for(Millis(3000));
  EXPECT_EQ(r.driver.common().speed_rpm, 0);
  EXPECT_FALSE(r.driver.common().running);
  EXPECT_EQ(r.driver.common().command, Command::stop);
}

TEST(UniclaDriver, SetRunStateFrameExact) {
  Rig r;
  r.start();
  r.driver.setpoint(3000, 1, r.now());
  const std::size_t from = r.bus.sent.size();
  const std::uint8_t seq = static_cast<std::uint8_t>(sent_frame(r.bus.sent.back()).sequence + 1);
  r.driver.command(Command::run_forward, 2, r.now());
  r.wait(2);
  Frame want;
  want.destination = 0x01;
  want.command = 0xC1;
  want.message_id = 0xC0;
  want.sequence = seq;
  want.payload = {0x0B, 0xB8};
  EXPECT_EQ(r.bus.sent[from], encode(want));
}

TEST(UniclaDriver, SpeedChangeWhileRunningIsSentAndConfirmedBySpeed) {
  Rig r;
  ASSERT_EQ(r.run_at(3000), WriteResult::ok);
  r.bus.run_for(Millis(4000));
  const std::size_t from = r.bus.sent.size();
  ASSERT_EQ(r.driver.setpoint(4500, 3, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(3), WriteResult::ok);
  const auto runs = r.sent_with(kRun, from);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].payload, (Bytes{0x11, 0x94}));  // 4500
  r.bus.run_for(Millis(3000));
  EXPECT_EQ(r.driver.common().speed_rpm, 4500);
}

// A PLC writes setpoint and run_forward in one request every cycle. While running that is two
// Set Run State writes for the same thing: one frame carries both, and both complete ok (not
// 0x0B for the first, superseded).
TEST(UniclaDriver, SetpointAndRunTogetherWhileRunningShareOneFrame) {
  Rig r;
  ASSERT_EQ(r.run_at(3000), WriteResult::ok);
  r.bus.run_for(Millis(4000));
  const std::size_t from = r.bus.sent.size();
  ASSERT_EQ(r.driver.setpoint(4500, 3, r.now()), WriteStatus::pending);
  ASSERT_EQ(r.driver.command(Command::run_forward, 4, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(4), WriteResult::ok);
  EXPECT_EQ(r.wait(3), WriteResult::ok);
  const auto runs = r.sent_with(kRun, from);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].payload, (Bytes{0x11, 0x94}));  // 4500
}

// A stop that supersedes an unconfirmed speed change leaves stop in force: a later setpoint is
// stored, not sent (it must not start the drive).
TEST(UniclaDriver, StopSupersedingASpeedChangeKeepsStopInForce) {
  Rig r;
  ASSERT_EQ(r.run_at(3000), WriteResult::ok);
  r.bus.run_for(Millis(4000));
  ASSERT_EQ(r.driver.setpoint(4500, 3, r.now()), WriteStatus::pending);
  ASSERT_EQ(r.driver.command(Command::stop, 4, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.driver.common().command, Command::stop);
  EXPECT_EQ(r.wait(3), WriteResult::no_response);  // superseded
  EXPECT_EQ(r.wait(4), WriteResult::ok);
  EXPECT_EQ(r.driver.common().command, Command::stop);
  r.bus.run_for(Millis(3000));
  const std::size_t from = r.bus.sent.size();
  EXPECT_EQ(r.driver.setpoint(2000, 5, r.now()), WriteStatus::done);
  r.bus.run_for(Millis(1000));
  EXPECT_TRUE(r.sent_with(kRun, from).empty());
  EXPECT_EQ(r.driver.common().speed_rpm, 0);
}

TEST(UniclaDriver, OutOfLimitsAndImpossibleCommandsAreRefusedLocally) {
  Rig r;
  // Before the running limits are read nothing can be judged.
  EXPECT_EQ(r.driver.setpoint(3000, 1, r.now()), WriteStatus::refused);
  EXPECT_EQ(r.driver.command(Command::run_forward, 2, r.now()), WriteStatus::refused);
  r.start();
  EXPECT_EQ(r.driver.setpoint(7000, 3, r.now()), WriteStatus::invalid_value);  // max 6000
  EXPECT_EQ(r.driver.setpoint(1000, 4, r.now()), WriteStatus::invalid_value);  // min 1500
  EXPECT_EQ(r.driver.setpoint(-5, 5, r.now()), WriteStatus::invalid_value);
  EXPECT_EQ(r.driver.command(Command::run_reverse, 6, r.now()), WriteStatus::invalid_value);
  // Setpoint still 0: cannot run at 0 rpm.
  EXPECT_EQ(r.driver.command(Command::run_forward, 7, r.now()), WriteStatus::invalid_value);
  EXPECT_EQ(r.driver.write(kOpState, Value{std::int64_t{1}}, 8, r.now()),
            WriteStatus::invalid_value);
  const std::size_t from = r.bus.sent.size();
  r.bus.run_for(Millis(1000));
  EXPECT_TRUE(r.sent_with(kRun, from).empty());
  EXPECT_TRUE(r.bus.completions.empty());
}

TEST(UniclaDriver, QuickStopIsAPlainStop) {
  Rig r;
  r.start();
  const std::size_t from = r.bus.sent.size();
  ASSERT_EQ(r.driver.command(Command::quick_stop, 1, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(1), WriteResult::ok);
  const auto runs = r.sent_with(kRun, from);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].payload, (Bytes{0x00, 0x00}));
}

TEST(UniclaDriver, MotorFaultMapsAndResetFaultClearsIt) {
  Rig r;
  ASSERT_EQ(r.run_at(3000), WriteResult::ok);
  r.bus.run_for(Millis(2000));
  r.sim.control("fault motor", r.now());  // Fault - Motor + ST over current
  r.bus.run_for(Millis(600));
  const CommonState& c = r.driver.common();
  EXPECT_TRUE(c.faults.has(Fault::over_current));
  EXPECT_EQ(most_severe(c.faults), Fault::over_current);
  EXPECT_EQ(c.native_fault, 7u);
  EXPECT_EQ(as_int(r.driver.values()[kMotorRunFlags]), 0x4000);
  // A run command is refused by a faulted drive: the next status shows the fault.
  EXPECT_EQ(r.driver.command(Command::run_forward, 3, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(3), WriteResult::refused);

  const std::size_t from = r.bus.sent.size();
  ASSERT_EQ(r.driver.command(Command::reset_fault, 4, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(4), WriteResult::ok);
  const auto acks = r.sent_with(kAck, from);
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_EQ(acks[0].command, 0xC1);
  EXPECT_TRUE(acks[0].payload.empty());  // "Acknowledge Faults: payload 0"
  EXPECT_TRUE(r.driver.common().faults.empty());
  EXPECT_EQ(r.driver.common().native_fault, 0u);
  EXPECT_EQ(as_int(r.driver.values()[kOpState]), 3);
}

TEST(UniclaDriver, AcknowledgeThatDoesNotClearIsRefused) {
  Rig r;
  r.start();
  r.sim.control("fault pressure", r.now());
  r.sim.control("sticky on", r.now());
  r.bus.run_for(Millis(600));
  EXPECT_TRUE(r.driver.common().faults.has(Fault::process_limit));
  EXPECT_EQ(r.driver.common().native_fault, 6u);
  ASSERT_EQ(r.driver.command(Command::reset_fault, 1, r.now()), WriteStatus::pending);
  const TimePoint sent = r.now();
  EXPECT_EQ(r.wait(1), WriteResult::refused);
  EXPECT_GE(r.now() - sent, Millis(2000));  // confirm_timeout_ms
}

TEST(UniclaDriver, IgnoredWriteEndsInNoResponse) {
  Rig r;
  r.start();
  r.sim.control("control off", r.now());  // the drive now ignores writes
  r.driver.setpoint(3000, 1, r.now());
  ASSERT_EQ(r.driver.command(Command::run_forward, 2, r.now()), WriteStatus::pending);
  EXPECT_EQ(r.wait(2), WriteResult::no_response);
  EXPECT_EQ(r.driver.common().command, Command::stop);  // restored
}

TEST(UniclaDriver, ControlDisabledInLimitsRefusesWritesAtOnce) {
  Rig r;
  r.sim.control("control off", r.now());
  r.start();
  EXPECT_EQ(as_int(r.driver.values()[kControlEnabled]), 0);
  r.driver.setpoint(3000, 1, r.now());
  EXPECT_EQ(r.driver.command(Command::run_forward, 2, r.now()), WriteStatus::refused);
  EXPECT_EQ(r.driver.command(Command::stop, 3, r.now()), WriteStatus::refused);
  EXPECT_EQ(r.driver.command(Command::reset_fault, 4, r.now()), WriteStatus::refused);
}

TEST(UniclaDriver, BadCrcIsResentIdentically) {
  Rig r;
  r.start();
  r.sim.control("corrupt 1", r.now());
  const std::size_t from = r.bus.sent.size();
  r.bus.run_for(Millis(600));
  ASSERT_GE(r.bus.sent.size(), from + 2);
  EXPECT_EQ(r.bus.sent[from], r.bus.sent[from + 1]);  // same frame, same sequence
  EXPECT_EQ(r.bus.bad_frames, 1);
  EXPECT_EQ(r.bus.retries, 1);
}

TEST(UniclaDriver, ForeignSequenceSourceAndDestinationAreDropped) {
  Rig r;
  r.start();
  TimePoint now = r.now() + Millis(1000);
  const auto ex = r.driver.next_exchange(now);
  ASSERT_TRUE(ex);
  const Frame req = sent_frame(ex->frame);
  Frame rep;
  rep.source = 0x01;
  rep.command = 0xC0;
  rep.message_id = kStatus;
  rep.sequence = static_cast<std::uint8_t>(req.sequence - 1);  // a late reply to an earlier read
  rep.payload = encode_status(r.sim.status(), ByteOrder::big);
  Bytes wire = encode(rep);
  RxVerdict v = r.driver.on_receive(wire, now);
  EXPECT_EQ(v.kind, RxKind::foreign);
  EXPECT_EQ(v.consumed, wire.size());
  rep.sequence = req.sequence;
  rep.source = 0x02;  // another drive
  wire = encode(rep);
  EXPECT_EQ(r.driver.on_receive(wire, now).kind, RxKind::foreign);
  rep.source = 0x01;
  rep.destination = 0x05;  // not for the master
  wire = encode(rep);
  EXPECT_EQ(r.driver.on_receive(wire, now).kind, RxKind::foreign);
  EXPECT_EQ(r.driver.on_receive(ex->frame, now).kind, RxKind::foreign);  // a request
  rep.destination = 0x00;
  rep.message_id = kBuild;  // right sequence, wrong message
  wire = encode(rep);
  EXPECT_EQ(r.driver.on_receive(wire, now).kind, RxKind::foreign);
  rep.message_id = kStatus;
  rep.payload.resize(10);  // checked but short: not a status
  wire = encode(rep);
  EXPECT_EQ(r.driver.on_receive(wire, now).kind, RxKind::noise);
  rep.payload = encode_status(r.sim.status(), ByteOrder::big);
  wire = encode(rep);
  // Split at every byte: incomplete until the EOF, then the reply.
  for (std::size_t n = 1; n < wire.size(); ++n) {
    const RxVerdict part = r.driver.on_receive(ByteView(wire).first(n), now);
    ASSERT_EQ(part.kind, RxKind::incomplete) << n;
    EXPECT_EQ(part.consumed, 0u);
  }
  v = r.driver.on_receive(wire, now);
  EXPECT_EQ(v.kind, RxKind::reply);
  EXPECT_EQ(v.consumed, wire.size());
  // Once answered, the same reply again is foreign.
  EXPECT_EQ(r.driver.on_receive(wire, now).kind, RxKind::foreign);
}

TEST(UniclaDriver, BadBytesGiveVerdictsThatConsume) {
  Rig r;
  const TimePoint now = r.now();
  const Bytes noise = {0x01, 0x02, 0x7E};
  RxVerdict v = r.driver.on_receive(noise, now);
  EXPECT_EQ(v.kind, RxKind::noise);
  EXPECT_EQ(v.consumed, 2u);
  const Bytes bad_crc = {0x7E, 0x01, 0x00, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0x00, 0x00, 0x7E};
  v = r.driver.on_receive(bad_crc, now);
  EXPECT_EQ(v.kind, RxKind::bad_checksum);
  EXPECT_GT(v.consumed, 0u);
}

TEST(UniclaDriver, CommLostFailsWritesAndRedoesStartUp) {
  Rig r;
  r.start();
  r.sim.control("silent on", r.now());
  r.driver.setpoint(3000, 1, r.now());
  ASSERT_EQ(r.driver.command(Command::run_forward, 2, r.now()), WriteStatus::pending);
  // The drive takes the write but never answers a read: no_response at the confirm deadline.
  EXPECT_EQ(r.wait(2), WriteResult::no_response);
  ASSERT_TRUE(r.bus.run_until([&] { return r.bus.comm_lost(); }, Millis(10000)));
  EXPECT_FALSE(r.driver.common().ready);
  ASSERT_EQ(r.driver.command(Command::reset_fault, 3, r.now()), WriteStatus::pending);
  r.bus.run_for(Millis(20));
  const std::size_t from = r.bus.sent.size();
  r.sim.control("silent off", r.now());
  ASSERT_TRUE(r.bus.run_until([&] { return r.driver.common().ready; }, Millis(3000)));
  const auto build = r.sent_with(kBuild, from);
  const auto limits = r.sent_with(kLimits, from);
  EXPECT_EQ(build.size(), 1u);
  EXPECT_EQ(limits.size(), 1u);
  EXPECT_FALSE(r.bus.comm_lost());
}

TEST(UniclaDriver, PendingWriteFailsOnCommLost) {
  Rig r;
  r.start();
  r.sim.control("silent on", r.now());
  r.driver.setpoint(3000, 1, r.now());
  ASSERT_EQ(r.driver.command(Command::run_forward, 2, r.now()), WriteStatus::pending);
  r.driver.on_comm_lost(r.now());  // before the write even went out
  std::vector<Completion> out;
  r.driver.take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].ticket, 2u);
  EXPECT_EQ(out[0].result, WriteResult::no_response);
}

TEST(UniclaDriver, LittleEndianFloatsFollowTheOption) {
  Settings little;
  little.byte_order = ByteOrder::little;
  Rig r(3, little, ByteOrder::little);
  r.start();
  EXPECT_DOUBLE_EQ(std::get<double>(r.driver.values()[kSuctionPressure]), 4.5);
  EXPECT_DOUBLE_EQ(std::get<double>(r.driver.values()[kDischargePressureHigh]), 28.0);
  EXPECT_EQ(as_int(r.driver.values()[kLimitMaxSpeed]), 6000);
  Rig mismatched(3, Settings{}, ByteOrder::little);
  mismatched.start();
  EXPECT_NE(std::get<double>(mismatched.driver.values()[kSuctionPressure]), 4.5);
  EXPECT_EQ(as_int(mismatched.driver.values()[kLimitMaxSpeed]), 6000);  // integers unaffected
}

TEST(UniclaDriver, TraitsFollowOptions) {
  Settings s;
  s.confirm_timeout = Millis(1500);
  Rig r(1, s);
  EXPECT_EQ(r.driver.traits().write_timeout, Millis(2500));
  EXPECT_GE(r.driver.traits().comm_timeout, Millis(3000));
}

TEST(UniclaFaults, MotorFlagsMapToUnifiedCodes) {
  EXPECT_TRUE(map_motor_flags(1u << 14).has(Fault::over_current));
  EXPECT_TRUE(map_motor_flags(1u << 9).has(Fault::over_voltage));
  EXPECT_TRUE(map_motor_flags(1u << 10).has(Fault::under_voltage));
  EXPECT_TRUE(map_motor_flags(1u << 11).has(Fault::drive_over_temperature));
  EXPECT_TRUE(map_motor_flags(1u << 4).has(Fault::motor_over_temperature));
  EXPECT_TRUE(map_motor_flags(1u << 12).has(Fault::stall));
  EXPECT_TRUE(map_motor_flags(1u << 5).has(Fault::overload));
  EXPECT_TRUE(map_motor_flags(1u << 0).empty());      // "X"
  EXPECT_TRUE(map_compressor_flags(0x000F).empty());  // bits 0-3 "X"
  EXPECT_TRUE(map_compressor_flags(0x0010).has(Fault::process_limit));
  EXPECT_TRUE(map_electrical_flags(1u << 11).empty());  // bits 11-15 "X"
  EXPECT_TRUE(map_electrical_flags(1u << 23).has(Fault::hardware_fault));
  EXPECT_TRUE(map_electrical_flags(1u << 0).has(Fault::hardware_fault));
}

TEST(UniclaFaults, OpStatesMapToUnifiedCodes) {
  Status s;
  const auto faults_of = [&s](OpState st) {
    s.op_state = static_cast<std::uint8_t>(st);
    return map_faults(s);
  };
  EXPECT_TRUE(faults_of(OpState::fault_compressor_safety).faults.has(Fault::process_limit));
  EXPECT_TRUE(faults_of(OpState::fault_motor).faults.has(Fault::other));  // no flag says more
  EXPECT_TRUE(faults_of(OpState::fault_fmc).faults.has(Fault::hardware_fault));
  EXPECT_TRUE(faults_of(OpState::fault_electrical).faults.has(Fault::hardware_fault));
  EXPECT_TRUE(faults_of(OpState::fault_configuration).faults.has(Fault::config_error));
  EXPECT_TRUE(faults_of(OpState::fault_xc_comms).faults.has(Fault::comm_lost));
  EXPECT_EQ(faults_of(OpState::fault_xc_comms).native, 11u);
  EXPECT_TRUE(faults_of(OpState::running).faults.empty());
  EXPECT_FALSE(faults_of(OpState::running).warning);
  EXPECT_TRUE(faults_of(OpState::wait_compressor_safety).warning);
  EXPECT_TRUE(faults_of(OpState::locked).warning);
  s.motor_run_flags = 1u << 14;
  const FaultView motor = faults_of(OpState::fault_motor);
  EXPECT_TRUE(motor.faults.has(Fault::over_current));
  EXPECT_FALSE(motor.faults.has(Fault::other));
  // The same flag while running is a warning, not a fault.
  const FaultView running = faults_of(OpState::running);
  EXPECT_TRUE(running.faults.empty());
  EXPECT_TRUE(running.warning);
}

TEST(UniclaSettings, ParsesOptionsAndDefaults) {
  std::string error;
  auto s = parse_settings(Options{}, error);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->byte_order, ByteOrder::big);
  EXPECT_EQ(s->attempts, 3);
  EXPECT_EQ(s->reply_timeout, Millis(100));
  s = parse_settings(Options({{"byte_order", std::string("little")},
                              {"retries", std::int64_t{0}},
                              {"reply_timeout_ms", std::int64_t{250}},
                              {"confirm_timeout_ms", std::int64_t{1000}}}),
                     error);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->byte_order, ByteOrder::little);
  EXPECT_EQ(s->attempts, 1);
  EXPECT_EQ(s->reply_timeout, Millis(250));
  EXPECT_EQ(s->confirm_timeout, Millis(1000));
  EXPECT_FALSE(parse_settings(Options({{"byte_order", std::string("middle")}}), error));
  EXPECT_NE(error.find("byte_order"), std::string::npos);
  EXPECT_EQ(kOptionSchema.size(), 4u);
}

}  // namespace
}  // namespace drivegate::unicla
