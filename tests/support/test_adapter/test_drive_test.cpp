// The test-drive plugin the core's tests run on: its frames byte for byte, the descriptor
// contract every adapter passes (the demo device runs at its speed through the real bus engine),
// and the simulator's answers.
#include <gtest/gtest.h>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "common_block.h"
#include "descriptor_contract.h"
#include "driver.h"
#include "simulator.h"

namespace drivegate::testdrive {
namespace {

using test::DescriptorContract;

const test::DescriptorFacts kFacts{.id = "test-drive",
                                   .options = kOptionSchema,
                                   .line = {9600, Parity::none, 8, 1, false},
                                   .address_min = 1,
                                   .address_max = 247,
                                   .default_address = 1,
                                   .streaming = false,
                                   .demo_options = {},
                                   .demo_rpm = 1500};
INSTANTIATE_TEST_SUITE_P(TestDrive, DescriptorContract, testing::Values(kFacts));

TEST(TestDriveCodec, FramesSumToZero) {
  // 3C 01 02 05 DC add up to 0x120: the sum byte is 0xE0. 3E 07 03 03 00 FA 24: 0x169, 0x97.
  EXPECT_EQ(encode(Request{1, Op::run_forward, 1500}), (Bytes{0x3C, 0x01, 0x02, 0x05, 0xDC, 0xE0}));
  const Bytes reply = encode(Reply{7, Op::run_reverse, 0x03, 0, -1500});
  EXPECT_EQ(reply, (Bytes{0x3E, 0x07, 0x03, 0x03, 0x00, 0xFA, 0x24, 0x97}));
  const auto d = decode_reply(reply);
  ASSERT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.frame, (Reply{7, Op::run_reverse, 0x03, 0, -1500}));
}

TEST(TestDriveCodec, RefusesWhatIsNotAFrame) {
  EXPECT_EQ(decode_request(Bytes{0x3C, 0x01}).status, DecodeStatus::incomplete);
  const auto noise = decode_request(Bytes{0x00, 0x3C});
  EXPECT_EQ(noise.status, DecodeStatus::bad);
  EXPECT_EQ(noise.consumed, 1u);
  const auto bad_sum = decode_request(Bytes{0x3C, 0x01, 0x02, 0x05, 0xDC, 0xE1});
  EXPECT_EQ(bad_sum.status, DecodeStatus::bad);
  EXPECT_EQ(bad_sum.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(bad_sum.consumed, 6u);
  Bytes unknown_op = {0x3C, 0x01, 0x09, 0x00, 0x00};
  unknown_op.push_back(sum_byte(unknown_op));
  EXPECT_EQ(decode_request(unknown_op).error, make_error_code(FrameError::bad_field));
}

TEST(TestDriveCodec, ARefusalEchoesTheOpAndCarriesNothing) {
  // 3F 02 06 00 00 00 00 adds up to 0x47: the sum byte is 0xB9.
  const Bytes refused = encode(refusal(2, Op::accel));
  EXPECT_EQ(refused, (Bytes{0x3F, 0x02, 0x06, 0x00, 0x00, 0x00, 0x00, 0xB9}));
  const auto d = decode_reply(refused);
  ASSERT_EQ(d.status, DecodeStatus::frame);
  EXPECT_TRUE(d.frame.refused);
  EXPECT_EQ(d.frame.op, Op::accel);
  // accel: 2.5 s, 25 in 100 ms units. 3C 01 06 00 19 adds up to 0x5C: 0xA4.
  EXPECT_EQ(encode(Request{1, Op::accel, 25}), (Bytes{0x3C, 0x01, 0x06, 0x00, 0x19, 0xA4}));
  // A request's start is not a reply's.
  EXPECT_EQ(decode_reply(encode(Request{1, Op::read, 0})).status, DecodeStatus::bad);
}

TEST(TestDriveSimulator, AnswersItsAddressAndRampsToTheSpeedAsked) {
  TestDriveSimulator sim(3);
  const TimePoint t0{};
  EXPECT_TRUE(sim.on_receive(encode(Request{4, Op::read, 0}), t0).empty());  // another's
  EXPECT_EQ(sim.on_receive(encode(Request{3, Op::run_forward, 1000}), t0),
            encode(Reply{3, Op::run_forward, kStateRunning, 0, 0}));
  sim.on_tick(t0);
  sim.on_tick(t0 + Millis(250));  // 2000 rpm/s: 500 rpm on
  EXPECT_EQ(sim.on_receive(encode(Request{3, Op::read, 0}), t0),
            encode(Reply{3, Op::read, kStateRunning, 0, 500}));
  EXPECT_EQ(sim.control("fault stall", t0), "ok fault=stall");
  EXPECT_EQ(sim.on_receive(encode(Request{3, Op::read, 0}), t0),
            encode(Reply{3, Op::read, 0, static_cast<std::uint8_t>(NativeFault::stall), 0}));
  EXPECT_EQ(sim.control("silent on", t0), "ok silent=on");
  EXPECT_TRUE(sim.on_receive(encode(Request{3, Op::reset, 0}), t0).empty());
  EXPECT_EQ(sim.control("bogus", t0).rfind("error: ", 0), 0u);
}

TEST(TestDriveSimulator, RefusesTheNextRequestsAndRampsInItsAccelTime) {
  TestDriveSimulator sim(1);
  const TimePoint t0{};
  EXPECT_EQ(sim.control("refuse 2", t0), "ok refuse=2");
  EXPECT_EQ(sim.on_receive(encode(Request{1, Op::run_forward, 3000}), t0),
            encode(refusal(1, Op::run_forward)));
  EXPECT_EQ(sim.on_receive(encode(Request{1, Op::accel, 30}), t0), encode(refusal(1, Op::accel)));
  EXPECT_NE(sim.control("state", t0).find(" running=0 fault=0 speed=0 target=0 accel=15 "),
            std::string::npos)
      << sim.control("state", t0);
  // Taken now: 3.0 s from 0 to 3000 rpm, 1000 rpm/s.
  EXPECT_EQ(sim.on_receive(encode(Request{1, Op::accel, 30}), t0),
            encode(Reply{1, Op::accel, 0, 0, 0}));
  EXPECT_EQ(sim.on_receive(encode(Request{1, Op::run_forward, 3000}), t0),
            encode(Reply{1, Op::run_forward, kStateRunning, 0, 0}));
  sim.on_tick(t0);
  sim.on_tick(t0 + Millis(500));
  EXPECT_EQ(sim.on_receive(encode(Request{1, Op::read, 0}), t0),
            encode(Reply{1, Op::read, kStateRunning, 0, 500}));
  EXPECT_NE(sim.control("state", t0).find(" running=1 "), std::string::npos);
  // A slow ramp, 10 rpm/s (300 s to 3000 rpm), moves in ticks of less than 1 rpm.
  EXPECT_EQ(sim.on_receive(encode(Request{1, Op::accel, 3000}), t0),
            encode(Reply{1, Op::accel, kStateRunning, 0, 500}));
  for (int tick = 1; tick <= 40; ++tick) sim.on_tick(t0 + Millis(500 + 50 * tick));
  EXPECT_EQ(sim.on_receive(encode(Request{1, Op::read, 0}), t0),
            encode(Reply{1, Op::read, kStateRunning, 0, 520}));
}

// Through the real bus engine: a setpoint is stored while stopped, a run is in force once the
// drive answered it, and the common block follows the drive's ramp to the speed asked.
TEST(TestDriveDriver, RunsAtTheSpeedAsked) {
  test::AdapterBench b(drivegate_adapter, {});
  ASSERT_TRUE(b.until_online(Millis(0), Millis(5000)));
  EXPECT_TRUE(b.stores_without_traffic(900));
  EXPECT_TRUE(b.run_forward_at(1200));
  EXPECT_EQ(b.read("command"), test::common_block::cmd::run_forward);
  EXPECT_EQ(b.read("setpoint_rpm"), 1200u);
  EXPECT_TRUE(b.until_reads("speed_rpm", 1200, Millis(3000)));
}

// A drive found running (started by another master: the run is not this driver's): the run it
// turns on is in force, at the speed it turned when first seen.
TEST(TestDriveDriver, ADriveFoundRunningShowsTheRunItTurnsOn) {
  test::AdapterBench b(drivegate_adapter, {});
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.sim->on_receive(encode(Request{1, Op::run_reverse, 700}), b.rig.now()),
            encode(Reply{1, Op::run_reverse, kStateRunning | kStateReverse, 0, 0}));
  ASSERT_TRUE(b.until_reads("command", test::common_block::cmd::run_reverse, Millis(2000)));
  EXPECT_NE(b.status() & test::common_block::kRunning, 0u);
  const auto setpoint = static_cast<std::int32_t>(b.read("setpoint_rpm"));
  EXPECT_GT(setpoint, 0);
  EXPECT_LE(setpoint, 700);
}

// accel_time (holding 16, 0.1 s): the drive's factory 1.5 s until written; a write goes out as
// accel at once and is in force once the drive answered it; a value the frame cannot carry is
// refused before the line.
TEST(TestDriveDriver, AccelTimeIsSentAndInForceOnceAnswered) {
  test::AdapterBench b(drivegate_adapter, {});
  ASSERT_TRUE(b.until_online());
  EXPECT_EQ(b.address_of("accel_time"), 16);
  EXPECT_EQ(b.read("accel_time"), 15u);
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write("accel_time", {25}), Outcome::ok);
  EXPECT_EQ(b.frames(asked).front(), encode(Request{1, Op::accel, 25}));
  EXPECT_EQ(b.read("accel_time"), 25u);
  EXPECT_TRUE(b.sim_has("accel=25"));
  EXPECT_EQ(b.write("accel_time", {0}), Outcome::invalid_value);
  EXPECT_EQ(b.read("accel_time"), 25u);
}

// accel_time_ms: the drive is set to it before anything else, and again once it is back after a
// silence (it may have been powered off).
TEST(TestDriveDriver, TheConfiguredAccelTimeIsSetEachTimeTheDriveIsReached) {
  test::AdapterBench b(drivegate_adapter, {.options = {{"accel_time_ms", "120000"}}});
  ASSERT_TRUE(b.until_online());
  ASSERT_FALSE(b.frames().empty());
  EXPECT_EQ(b.frames().front(), encode(Request{1, Op::accel, 1200}));
  EXPECT_EQ(b.read("accel_time"), 1200u);
  EXPECT_TRUE(b.sim_has("accel=1200"));
  EXPECT_EQ(b.count(encode(Request{1, Op::accel, 1200})), 1u);
  ASSERT_EQ(b.control("silent on"), "ok silent=on");
  b.rig.run_for(Millis(5000));
  ASSERT_NE(b.status() & test::common_block::kCommLost, 0u);
  ASSERT_EQ(b.control("silent off"), "ok silent=off");
  const TimePoint back = b.rig.now();
  b.rig.run_for(Millis(6000));
  ASSERT_NE(b.status() & test::common_block::kOnline, 0u);
  EXPECT_EQ(b.frames(back).front(), encode(Request{1, Op::accel, 1200}));
}

// A write the drive does not answer goes again each turn until its deadline (1.8 s: the
// gateway's 2 s backstop less the margin, before comm_lost at 3 s), and fails then; one answered
// in time is in force.
TEST(TestDriveDriver, AnUnansweredWriteIsResentUntilItsDeadline) {
  test::AdapterBench b(drivegate_adapter, {});
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.control("silent on"), "ok silent=on");
  const TimePoint asked = b.rig.now();
  const auto deaf = b.start_write({test::common_block::cmd::run_forward, 900});
  b.rig.run_for(Millis(1000));
  ASSERT_EQ(b.control("silent off"), "ok silent=off");
  b.rig.run_for(Millis(1000));
  ASSERT_TRUE(deaf->settled());
  EXPECT_EQ(deaf->result, Outcome::ok);
  EXPECT_GT(b.count(encode(Request{1, Op::run_forward, 900}), asked), 3u);  // turns of 3
  EXPECT_EQ(b.read("command"), test::common_block::cmd::run_forward);

  ASSERT_EQ(b.control("silent on"), "ok silent=on");
  const TimePoint stop_asked = b.rig.now();
  const auto lost = b.start_write({test::common_block::cmd::stop});
  b.rig.run_for(Millis(1700));
  EXPECT_FALSE(lost->settled());
  b.rig.run_for(Millis(500));  // its deadline, or the gateway's backstop at 2 s
  ASSERT_EQ(b.status() & test::common_block::kCommLost, 0u);
  ASSERT_TRUE(lost->settled());
  EXPECT_EQ(lost->result, Outcome::no_response);
  EXPECT_GT(b.count(encode(Request{1, Op::stop, 0}), stop_asked), 3u);
  // Nothing of it went out after its send-by (1.8 s) less a turn of attempts (0.3 s) began: the
  // drive heard again at once would otherwise stop after the client was told it failed.
  for (const TimePoint t : b.times_of(encode(Request{1, Op::stop, 0}), stop_asked)) {
    EXPECT_LE(t - stop_asked, Millis(1800)) << "sent after its send-by";
  }
}

// A run the client was told failed is never carried out: the drive deaf until the write fails,
// heard again at once after, never gets it (a resend's attempts never outlast the deadline).
TEST(TestDriveDriver, ARunTheClientWasToldFailedIsNeverCarriedOut) {
  test::AdapterBench b(drivegate_adapter, {});
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.control("silent on"), "ok silent=on");
  const auto run = b.start_write({test::common_block::cmd::run_forward, 900});
  for (int ms = 0; ms < 3000 && !run->settled(); ms += 5) b.rig.run_for(Millis(5));
  ASSERT_TRUE(run->settled());
  EXPECT_EQ(run->result, Outcome::no_response);
  ASSERT_EQ(b.control("silent off"), "ok silent=off");
  b.rig.run_for(Millis(1000));
  EXPECT_TRUE(b.sim_has("running=0")) << b.control("state");
  EXPECT_TRUE(b.sim_has("target=0")) << b.control("state");
  EXPECT_EQ(b.read("command"), test::common_block::cmd::stop);
}

// A refusal is counted as a NACK and the request resent; the write is in force once taken.
TEST(TestDriveDriver, ARefusedRequestIsResent) {
  test::AdapterBench b(drivegate_adapter, {});
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.control("refuse 2"), "ok refuse=2");
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({test::common_block::cmd::run_forward, 900}), Outcome::ok);
  EXPECT_EQ(b.count(encode(Request{1, Op::run_forward, 900}), asked), 3u);
  EXPECT_EQ(b.read("nacks"), 2u);  // as a PLC reads them
  EXPECT_EQ(b.read("command"), test::common_block::cmd::run_forward);
}

// What the drive cannot do is refused before the line, the whole request with it: reverse on a
// one-way drive (0x03), a run while it is tripped (0x04) until a reset cleared the fault.
TEST(TestDriveDriver, RefusesWhatTheDriveCannotDo) {
  test::AdapterBench one_way(drivegate_adapter, {.options = {{"one_way", "true"}}});
  ASSERT_TRUE(one_way.until_online());
  const TimePoint asked = one_way.rig.now();
  EXPECT_EQ(one_way.write({test::common_block::cmd::run_reverse, 900}), Outcome::invalid_value);
  EXPECT_EQ(one_way.count(encode(Request{1, Op::run_reverse, 900}), asked), 0u);
  EXPECT_EQ(one_way.read("setpoint_rpm"), 0u);
  EXPECT_EQ(one_way.write({test::common_block::cmd::run_forward, 900}), Outcome::ok);

  test::AdapterBench b(drivegate_adapter, {});
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.control("fault stall"), "ok fault=stall");
  ASSERT_TRUE(b.until_reads("native_fault", 2, Millis(2000)));
  EXPECT_EQ(b.write({test::common_block::cmd::run_forward, 900}), Outcome::refused);
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
  EXPECT_EQ(b.write({test::common_block::cmd::reset_fault}), Outcome::ok);
  EXPECT_EQ(b.write({test::common_block::cmd::run_forward, 900}), Outcome::ok);
  EXPECT_TRUE(b.until_reads("speed_rpm", 900, Millis(3000)));
}

}  // namespace
}  // namespace drivegate::testdrive
