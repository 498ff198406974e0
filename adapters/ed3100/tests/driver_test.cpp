// The driver against the simulator on the real bus engine (bench.h): the poll plan in the
// document's own frames and at their times, the registers a PLC reads, resends, comm_lost and
// recovery, both reply forms, noise and foreign frames, and the broadcast address.
#include <gtest/gtest.h>

#include <algorithm>

#include "bench.h"
#include "late_reply_contract.h"

namespace drivegate::ed3100 {
namespace {

using test::LateReplyContract;

// Late replies (late_reply_contract.h): timeout_ms 100 (the default), answering 130 ms late in
// the standard Modbus form, whose reads carry no register echo.
const test::LateReplyFacts kLate{.id = "ed3100", .late = 130ms, .sim_commands = {"form standard"}};
INSTANTIATE_TEST_SUITE_P(Ed3100, LateReplyContract, testing::Values(kLate));

const TimePoint kStart = TimePoint{} + std::chrono::hours(1);  // the rig's clock at start()

using Ed3100Driver = test::ReadyBench<Bench>;

TEST_F(Ed3100Driver, StartupReadsTheParameterThenTheFaultWordAndTheMonitors) {
  // The start-up read of 00-06 is the document's own frame; then 0x0E01 and the monitors, sent
  // with 00 00 as the document prints them.
  const auto f = b.frames();
  ASSERT_GE(f.size(), 6u);
  EXPECT_EQ(f[0], kReadParam);
  EXPECT_EQ(f[1], kReadFault);
  EXPECT_EQ(f[2], kReadMonitor);
  EXPECT_EQ(f[3], encode_read(0x1F, 0x0D01, 0));
  EXPECT_EQ(f[4], encode_read(0x1F, 0x0D02, 0));
  EXPECT_EQ(f[5], encode_read(0x1F, 0x0D03, 0));
  EXPECT_EQ(f.size(), 6u);
  EXPECT_EQ(b.read("retries"), 0u);

  // Document, "STX / END": at least 10 ms of silence before every frame. The first waits 10 ms
  // from the line opening; every next one goes 10 ms after the last byte of the reply before it.
  const auto& sent = b.rig.sent();
  const auto& answers = b.rig.answers();
  ASSERT_EQ(answers.size(), sent.size());
  EXPECT_EQ(sent[0].at, kStart + 10ms);
  for (std::size_t i = 0; i + 1 < sent.size(); ++i) {
    const TimePoint reply_end = answers[i].at + b.on_wire(answers[i].bytes.size());
    EXPECT_EQ(sent[i + 1].at - reply_end, 10ms) << "frame " << i + 1;
  }

  EXPECT_EQ(b.read("param_00_06"), 0x1088u);
  EXPECT_EQ(b.read("monitor_0d00_raw"), 0x1084u);
  EXPECT_EQ(b.read("monitor_0d00_format"), 0x4148u);
  EXPECT_FLOAT_EQ(b.read_f32("monitor_0d00"), 42.28f);  // "42.28 Hz, stopped"
  EXPECT_FLOAT_EQ(b.read_f32("monitor_0d03"), 537.0f);
  EXPECT_EQ(b.input(kFaultCodePoint), 0xFFFF);  // no fault
  EXPECT_EQ(b.read("state_word"), 0x0148u);
  EXPECT_EQ(b.read("commanded_direction"), 1u);
  EXPECT_EQ(b.read("running"), 0u);
  EXPECT_EQ(b.read_i16("speed_rpm"), 0);  // the stopped bit: 42.28 is the reference on display
  EXPECT_EQ(b.status(), kOnline);
  EXPECT_EQ(b.read("fault_code"), 0u);
  EXPECT_EQ(b.read("native_fault"), 0u);

  // The next cycles, every 500 ms from the first (asked for at start), do not read the parameter
  // again.
  b.rig.run_for(1000ms);
  EXPECT_EQ(b.times_of(kReadFault),
            (std::vector<TimePoint>{sent[1].at, kStart + 500ms, kStart + 1000ms}));
  const auto next = b.frames(kStart + 500ms);
  ASSERT_GE(next.size(), 5u);
  EXPECT_EQ(next[0], kReadFault);
  EXPECT_EQ(next[1], kReadMonitor);
  EXPECT_EQ(b.count(kReadParam), 1u);
}

// A drive found running (the gateway restarted, or this device was changed by a
// reload) is shown as it runs: the command in force is its commanded direction, the setpoint its
// speed; nothing is sent to it, and a new setpoint goes to the running drive's 0x2001 at once.
TEST(Ed3100DriverFromPowerOn, ADriveFoundRunningIsShownAsItRunsNeverAsStopped) {
  Bench b;
  ASSERT_EQ(b.control("run reverse 2500").rfind("ok", 0), 0u);  // 25.00 Hz, started at its keypad
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.read("command"), cmd::run_reverse);
  EXPECT_EQ(b.read_i16("setpoint_rpm"), 750);  // 25 Hz on 4 poles
  EXPECT_EQ(b.read_i16("speed_rpm"), -750);
  EXPECT_NE(b.status() & kRunning, 0u);
  EXPECT_TRUE(b.writes().empty());  // nothing was sent to the drive
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.write({900}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(b.writes(asked).size(), 1u);
  EXPECT_EQ(b.writes(asked)[0][2], 0x20);  // 0x2001: the running drive's reference
  EXPECT_EQ(b.writes(asked)[0][3], 0x01);
  EXPECT_TRUE(b.sim_has("running=1"));
}

TEST_F(Ed3100Driver, ASilentDriveIsResentToThenCommLostThenStartsUpAgain) {
  b.control("silent on");
  const TimePoint from = b.rig.now();
  EXPECT_EQ(b.write({cmd::stop}), Outcome::no_response);
  // attempts = 3, each waiting timeout_ms = 100 from the last byte written (8 bytes at 9600 8E1:
  // 9.17 ms, counted in whole ms), then the engine's guard time (100 ms again).
  const auto stops = b.times_of(kStop, from);
  ASSERT_EQ(stops.size(), 3u);
  EXPECT_EQ(stops[1] - stops[0], 209ms);
  EXPECT_EQ(stops[2] - stops[1], 209ms);

  // comm_timeout_ms = 3000 without a good frame: comm_lost (the engine looks every 100 ms).
  const TimePoint last_good = b.rig.answers().back().at;
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 5s));
  EXPECT_GE(b.rig.now() - last_good, 3000ms);
  EXPECT_LE(b.rig.now() - last_good, 3200ms);
  EXPECT_EQ(b.status() & kOnline, 0u);
  EXPECT_EQ(b.read("fault_code"), 1u);  // comm_lost
  // Writes answer 0x0B at once and send nothing.
  const TimePoint lost = b.rig.now();
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::no_response);
  b.rig.run_for(500ms);
  EXPECT_TRUE(b.writes(lost).empty());

  b.control("silent off");
  const TimePoint back = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 10s));
  // The start-up sequence again: the parameter before the fault word.
  const auto after = b.frames(back);
  const auto param = std::find(after.begin(), after.end(), kReadParam);
  const auto fault = std::find(after.begin(), after.end(), kReadFault);
  ASSERT_NE(param, after.end());
  EXPECT_LT(param, fault);
  EXPECT_EQ(b.read("fault_code"), 0u);
}

TEST_F(Ed3100Driver, ABadChecksumIsResentIdenticallyAtOnce) {
  ASSERT_EQ(b.control("corrupt 1"), "ok corrupt=1");
  const TimePoint from = b.rig.now();
  b.rig.run_for(500ms);
  const auto& sent = b.rig.sent();
  const auto first = std::find_if(sent.begin(), sent.end(),
                                  [&](const test::SimLine::Frame& f) { return f.at >= from; });
  ASSERT_NE(first, sent.end());
  ASSERT_NE(first + 1, sent.end());
  // The next cycle's fault read, answered with a bad CRC, goes again 10 ms after that reply.
  EXPECT_EQ(first->bytes, kReadFault);
  EXPECT_EQ((first + 1)->bytes, kReadFault);
  const auto& bad = b.rig.answers()[static_cast<std::size_t>(first - sent.begin())];
  EXPECT_EQ((first + 1)->at - (bad.at + b.on_wire(bad.bytes.size())), 10ms);
  EXPECT_EQ(b.read("bad_checksum"), 1u);
  EXPECT_EQ(b.read("retries"), 1u);
  EXPECT_EQ(b.read("timeouts"), 0u);
  EXPECT_EQ(b.status(), kOnline);  // one bad CRC is not a lost drive
}

TEST(Ed3100DriverFromPowerOn, StandardFormRepliesAreAccepted) {
  Bench b({{"parameters", "00-06"}, {"sim_reply_form", "standard"}});
  ASSERT_TRUE(b.ready());
  // A byte count (02) where the document's form echoes the register.
  EXPECT_EQ(
      b.rig.answers().at(0).bytes,
      encode_read_reply(0x1F, 0x0006, std::vector<std::uint16_t>{0x1088}, ReadForm::standard));
  EXPECT_EQ(b.rig.answers().at(0).bytes.at(2), 0x02);
  EXPECT_EQ(b.read("param_00_06"), 0x1088u);
  EXPECT_FLOAT_EQ(b.read_f32("monitor_0d00"), 42.28f);
  EXPECT_EQ(b.read("state_word"), 0x0148u);
  EXPECT_EQ(b.read("retries"), 0u);
  EXPECT_EQ(b.read("bad_checksum"), 0u);
}

TEST(Ed3100DriverFromPowerOn, NoiseAndForeignFramesBeforeTheReplyAreSkipped) {
  Bench b;
  // Before every reply two bytes of noise; before the parameter's, a good reply from drive 05
  // and one from this drive naming another register.
  const Bytes from_05 =
      encode_read_reply(0x05, 0x0006, std::vector<std::uint16_t>{1}, ReadForm::document);
  const Bytes other_register =
      encode_read_reply(0x1F, 0x0007, std::vector<std::uint16_t>{1}, ReadForm::document);
  b.rig.line().device_filter = [&](Bytes reply) {
    Bytes out = {0xAA, 0x55};
    if (reply.size() > 3 && reply[1] == kFnRead && reply[2] == 0x00) {
      out.insert(out.end(), from_05.begin(), from_05.end());
      out.insert(out.end(), other_register.begin(), other_register.end());
    }
    out.insert(out.end(), reply.begin(), reply.end());
    return out;
  };
  ASSERT_TRUE(b.ready());
  EXPECT_EQ(b.read("param_00_06"), 0x1088u);
  EXPECT_FLOAT_EQ(b.read_f32("monitor_0d00"), 42.28f);
  EXPECT_EQ(b.read("foreign_frames"), 2u);
  EXPECT_EQ(b.read("retries"), 0u);
  EXPECT_EQ(b.read("timeouts"), 0u);
  EXPECT_EQ(b.read("bad_checksum"), 0u);
  EXPECT_EQ(b.count(kReadParam), 1u);
}

TEST_F(Ed3100Driver, ATripIsFaultOtherWithTheRawCode) {
  ASSERT_EQ(b.control("fault 0x12"), "ok fault=0x0012");
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kFaulted) != 0; }, 1s));
  // The fault code table is not legible (specs README): every code is `other`, raw beside it.
  EXPECT_EQ(b.read("fault_code"), kFaultOther);
  EXPECT_EQ(b.read("fault_mask"), 1u << kFaultOther);
  EXPECT_EQ(b.read("native_fault"), 0x12u);
  EXPECT_EQ(b.input(kFaultCodePoint), 0x12);
  EXPECT_EQ(b.read("state_word") & (1u << 5), 1u << 5);  // "Failure"
  EXPECT_EQ(b.status() & kOnline, kOnline);              // a tripped drive still answers

  EXPECT_EQ(b.control("clear"), "ok");
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kFaulted) == 0; }, 1s));
  EXPECT_EQ(b.read("native_fault"), 0u);
  EXPECT_EQ(b.input(kFaultCodePoint), 0xFFFF);
}

// Address 0 reaches every drive and none answers (document, "00H"): nothing is polled, a write
// goes out once without waiting for a reply and counts as taken, and the device never goes
// comm_lost.
TEST(Ed3100DriverFromPowerOn, TheBroadcastAddressIsNeverPolledAndItsWritesAreUnanswered) {
  test::BusRig rig(drivegate_adapter);
  Device& all = rig.add_device("all", 0);
  Simulator& sim = rig.add_simulator(0x1F);
  rig.start();
  rig.run_for(2s);
  EXPECT_TRUE(rig.sent().empty());
  EXPECT_EQ(rig.write_and_wait(all, Table::holding, kCommandRegister, {cmd::run_forward}),
            Outcome::ok);
  ASSERT_EQ(rig.sent().size(), 1u);
  const std::uint16_t forward[] = {0x001E, 0x0000};  // run forward at the reference in force
  EXPECT_EQ(rig.sent()[0].bytes, encode_write_multiple(0x00, 0x2000, forward));
  EXPECT_TRUE(rig.answers().empty());
  EXPECT_EQ(rig.read(all, "command"), std::vector<std::uint16_t>{cmd::run_forward});
  rig.run_for(10s);
  EXPECT_NE(sim.control("state", rig.now()).find("running=1"), std::string::npos);
  EXPECT_EQ(rig.sent().size(), 1u);
  EXPECT_EQ(rig.read(all, "status")[0] & kCommLost, 0);
}

}  // namespace
}  // namespace drivegate::ed3100
