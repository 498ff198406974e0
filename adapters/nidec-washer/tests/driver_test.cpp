// The driver against the simulator on the real bus engine (bench.h): the ping handshake, the poll
// plan, resends, bad bytes, comm_lost and recovery, and the common block a PLC reads.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>

#include "bench.h"
#include "late_reply_contract.h"

namespace drivegate::nidec {
namespace {

using test::LateReplyContract;

// Late replies (late_reply_contract.h): the reply timeout of section 6, 100 ms, answered 130 ms
// late.
const test::LateReplyFacts kLate{.id = "nidec-washer", .late = 130ms};
INSTANTIATE_TEST_SUITE_P(NidecWasher, LateReplyContract, testing::Values(kLate));

TEST(NidecDriverFromPowerOn, PingsFirstThenPollsEvery500ms_5_1_section6) {
  Bench b;
  const TimePoint t0 = b.rig.now();
  b.rig.run_for(1900ms);
  const auto& sent = b.rig.sent();
  ASSERT_EQ(sent.size(), 4u);
  EXPECT_EQ(sent[0].bytes, kPing7);
  // The first frame waits for the inter-frame gap after the line came up: two characters,
  // rounded up to 5 ms; each next one is due 500 ms after the one before was asked for.
  EXPECT_EQ(sent[0].at, t0 + 5ms);
  for (std::size_t i = 1; i < sent.size(); ++i) {
    EXPECT_EQ(sent[i].bytes, kPoll) << i;
    EXPECT_EQ(sent[i].at, t0 + static_cast<int>(i) * 500ms) << i;
  }
  EXPECT_NE(b.status() & kOnline, 0u);
  EXPECT_EQ(b.read("inverter_version"), 0x0107u);
  EXPECT_EQ(b.read("platform"), 7u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.read("frames_good"), 4u);
  EXPECT_EQ(b.drive->driver().traits().comm_timeout, 6000ms);  // section 6
}

TEST(NidecDriverFromPowerOn, OptionsShapeThePingTheAccelTimeAndTheResends_5_1_section6) {
  // Section 6: a frame every second at least, whatever the device's poll interval says.
  Bench b({.options = {{"platform", "8"},
                       {"empty_raw_weight", "300"},
                       {"accel_time_ms", "5040"},
                       {"attempts", "4"}},
           .poll = 5000ms});
  ASSERT_TRUE(b.ready());
  const Bytes ping8{0xA5, 0x02, 0x08, 0x01, 0x2C, 0x00, 0x00, 0x00, 0x00, 0x00, 0x82};
  EXPECT_EQ(b.rig.sent().at(0).bytes, ping8);
  EXPECT_TRUE(b.sim_has("platform=8 empty_raw_weight=300"));
  EXPECT_EQ(b.read("platform"), 8u);
  EXPECT_EQ(b.read("accel_time"), 50u);  // 5.0 s: 5040 ms rounded to 100 ms units (5.3)
  b.rig.run_for(2s);
  const auto polls = b.times_of(kPoll);
  ASSERT_GE(polls.size(), 2u);
  EXPECT_EQ(polls[1] - polls[0], 1000ms);

  // Silent: four identical sends a turn, each 100 ms (section 6) after the echo of the one
  // before came back (11 bytes at 4800 8O1), and the engine's 100 ms guard time after that.
  b.control("silent on");
  const TimePoint from = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.read("timeouts") == 4; }, 2s));
  const auto resends = b.times_of(kPoll, from);
  ASSERT_GE(resends.size(), 4u);
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_EQ(resends[i] - resends[i - 1], unanswered_attempt(100ms) + b.on_wire(11)) << i;
  }
  EXPECT_EQ(b.read("retries"), 3u);  // then a new turn, the same poll (section 6)
}

TEST(NidecDriverFromPowerOn, ACommandBeforeTheHandshakeWaitsForThePing_5_1) {
  Bench b;
  // The ping is waiting for its inter-frame gap: nothing has been answered yet.
  ASSERT_EQ(b.status() & kOnline, 0u);
  const auto w = b.start_write({cmd::run_forward, 800});
  EXPECT_FALSE(w->settled());
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  const auto f = b.frames();
  ASSERT_GE(f.size(), 2u);
  EXPECT_EQ(f[0], kPing7);
  EXPECT_EQ(f[1], kCw800);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

using NidecDriver = test::ReadyBench<Bench>;

TEST_F(NidecDriver, ANackIsResentIdentically_5_16) {
  b.control("nack 1");
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  const auto f = b.frames(from);
  ASSERT_GE(f.size(), 2u);
  EXPECT_EQ(f[0], kStop);
  EXPECT_EQ(f[1], kStop);
  const auto stops = b.times_of(kStop, from);
  // At once: the NACK came back, so the engine does not wait out the 100 ms.
  EXPECT_LT(stops[1] - stops[0], 100ms);
  EXPECT_EQ(b.read("nacks"), 1u);
  EXPECT_EQ(b.read("timeouts"), 0u);
}

TEST_F(NidecDriver, ABadChecksumIsResent_4_2) {
  b.control("corrupt 2");
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_EQ(b.frames(from), (std::vector<Bytes>{kStop, kStop, kStop}));
  EXPECT_EQ(b.read("bad_checksum"), 2u);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

TEST_F(NidecDriver, NoiseAndStaleRepliesAreDropped_section2) {
  // Noise before every reply, and a stale brake ACK: each poll's own ACK still completes it.
  const Bytes stale = encode_reply(Mode::brake, {0, 0, 0, 0});
  const Bytes noise = {0x00, 0x13};
  b.rig.line().device_filter = [&](Bytes r) {
    Bytes out;
    out.reserve(noise.size() + stale.size() + r.size());
    for (const Bytes& part : std::array<Bytes, 3>{noise, stale, r}) {
      out.insert(out.end(), part.begin(), part.end());
    }
    return out;
  };
  const std::uint32_t good = b.read("frames_good");
  b.rig.run_for(1200ms);                       // the polls at 500 and 1000 ms, and their replies
  EXPECT_EQ(b.read("frames_good"), good + 2);  // the two polls' ACKs
  EXPECT_EQ(b.read("foreign_frames"), 2u);     // the two stale ones, well formed but not awaited
  EXPECT_EQ(b.read("timeouts"), 0u);
  EXPECT_EQ(b.read("retries"), 0u);
  EXPECT_EQ(b.read("bad_checksum"), 0u);
  EXPECT_NE(b.status() & kOnline, 0u);
}

TEST_F(NidecDriver, ASilentInverterIsResentToThenTheWriteFailsThenCommLost_section6) {
  b.control("silent on");
  const TimePoint t0 = b.rig.now();
  const auto w = b.start_write({cmd::stop});
  EXPECT_EQ(b.rig.wait(w), Outcome::no_response);
  // Failed by the driver's own 2.5 s deadline (once the attempt under way when it passed has
  // ended), before the gateway's 3 s one.
  EXPECT_LT(b.rig.now() - t0, 3000ms);
  const auto f = b.frames(t0);
  const auto stops = static_cast<std::size_t>(std::count(f.begin(), f.end(), kStop));
  EXPECT_GE(stops, 10u);  // one send every 225 ms (timeout and guard) or so, for 2.5 s
  EXPECT_TRUE(std::all_of(f.begin(), f.begin() + static_cast<long>(stops),
                          [](const Bytes& x) { return x == kStop; }));
  const TimePoint failed = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 7s));
  EXPECT_EQ(b.count(kStop, failed), 0u);  // never sent again once the PLC was told it failed
  EXPECT_EQ(b.status() & kOnline, 0u);
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::comm_lost));

  b.control("silent off");
  const TimePoint back = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kOnline) != 0; }, 6s));
  const auto again = b.frames(back);
  ASSERT_FALSE(again.empty());
  // 5.1: the ping again after a reconnect, and nothing but pings until it is answered.
  EXPECT_TRUE(std::all_of(again.begin(), again.end(), [](const Bytes& x) { return x == kPing7; }));
  EXPECT_EQ(b.status() & kCommLost, 0u);
}

// Section 6: "Master needs resend previous frame after 100ms did not get reply ... This repeat
// can last for 6 seconds." What goes on the wire to a silent inverter, as the README says it
// ("Resends, measured"): within a turn a resend every 225 ms (the frame and its echo, 25 ms at
// 4800 8O1, the 100 ms reply timeout, and the engine's 100 ms guard after it, which keeps a late
// reply from being taken for the resend's); `attempts` (3) a turn; the second turn at once, then
// the engine's back-off of a silent device, 1 s then 2 s (poll_ms doubling). Twelve sends in
// the 6 s before comm_lost, and no silence on the wire near the 6 s after which the inverter
// stops by itself (section 7).
TEST_F(NidecDriver, ASilentInverterIsResentAtTheCadenceTheReadmeStates_section6) {
  ASSERT_TRUE(b.after_next_poll());
  b.control("silent on");
  const TimePoint t0 = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 8s));
  const TimePoint lost = b.rig.now();
  const auto f = b.frames(t0);
  EXPECT_TRUE(std::all_of(f.begin(), f.end(), [](const Bytes& x) { return x == kPoll; }));
  const auto sent = b.times_of(kPoll, t0);
  ASSERT_EQ(sent.size(), 12u);
  const auto frame = b.on_wire(kPoll.size());  // its echo comes back as it goes out
  const auto resend = frame + 100ms + 100ms;   // reply timeout, then the guard
  const auto between = [&](std::size_t i) { return sent.at(i) - sent.at(i - 1); };
  for (const std::size_t i : {1, 2, 3, 4, 5, 7, 8, 10, 11}) {
    EXPECT_EQ(between(i), resend) << "send " << i;
  }
  // After the second and third turns: the last timeout, then the back-off from there.
  EXPECT_EQ(between(6), frame + 100ms + 1000ms);
  EXPECT_EQ(between(9), frame + 100ms + 2000ms);
  EXPECT_EQ(std::chrono::round<std::chrono::microseconds>(resend), 225208us);
  EXPECT_LT(lost - sent.back(), 1s);
  EXPECT_GE(lost - t0, 6s);
}

TEST_F(NidecDriver, CommLostStopsAndDoesNotResumeMotion_section7) {
  ASSERT_TRUE(b.running_at(800));
  b.control("silent on");
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 7s));
  // Section 7: the inverter stopped the motor by itself after 6 s of silence.
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.status() & kRunning, 0u);
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  EXPECT_EQ(b.read("setpoint_rpm"), 800u);  // what the next run carries
  b.control("silent off");
  const TimePoint back = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kOnline) != 0; }, 6s));
  b.rig.run_for(2s);
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  EXPECT_EQ(b.read("command"), cmd::stop);
  EXPECT_EQ(b.count(kCw800, back), 0u);
  EXPECT_TRUE(b.sim_has("motion=stopped"));
}

TEST_F(NidecDriver, WritesWhileCommLostAre0x0BAndFailWhatWasQueued) {
  b.control("silent on");
  b.rig.run_for(5500ms);
  ASSERT_EQ(b.status() & kCommLost, 0u);
  // Queued half a second before comm_lost: failed by it, not left to run later.
  const auto w = b.start_write({cmd::stop});
  EXPECT_EQ(b.rig.wait(w, 1s), Outcome::no_response);
  EXPECT_NE(b.status() & kCommLost, 0u);
  EXPECT_EQ(b.start_write({cmd::run_forward, 800})->result, Outcome::no_response);
  EXPECT_EQ(b.read("setpoint_rpm"), 0u);
}

TEST_F(NidecDriver, FaultsReachTheCommonBlockAndClearAfter4s_section8) {
  b.control("fault 0x18");  // stall + over-current
  ASSERT_TRUE(b.after_next_poll());
  EXPECT_EQ(b.read("native_fault"), 0x18u);
  EXPECT_EQ(b.read("fault_mask"), (1u << static_cast<unsigned>(Fault::stall)) |
                                      (1u << static_cast<unsigned>(Fault::over_current)));
  EXPECT_EQ(b.read("fault_code"), static_cast<std::uint32_t>(Fault::over_current));
  EXPECT_EQ(b.read("error_bits"), 0x18u);
  EXPECT_NE(b.status() & kFaulted, 0u);
  b.rig.run_for(4s);
  EXPECT_EQ(b.read("native_fault"), 0u);
  EXPECT_EQ(b.read("fault_mask"), 0u);
  EXPECT_EQ(b.status() & kFaulted, 0u);
  EXPECT_EQ(b.write({cmd::run_forward, 800}), Outcome::ok);
}

TEST_F(NidecDriver, SpeedFollowsTheRampAndIsUnsigned_5_4) {
  ASSERT_EQ(b.write({cmd::run_reverse, 800}), Outcome::ok);
  b.rig.run_for(1600ms);  // half way up the 3.0 s ramp
  EXPECT_NEAR(b.read("speed_rpm"), 400, 60);
  b.rig.run_for(2s);
  EXPECT_EQ(b.read("speed_rpm"), 800u);  // the protocol has no sign: CCW reads positive
  EXPECT_NE(b.status() & kRunning, 0u);
}

}  // namespace
}  // namespace drivegate::nidec
