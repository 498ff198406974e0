// The driver against the simulator on simulated time: exact frames on the wire.
#include "driver.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "codec.h"
#include "config.h"
#include "error_codes.h"
#include "loopback.h"
#include "simulator.h"

namespace drivegate::mdriver {
namespace {

using namespace std::chrono_literals;

// Section 3 No.1: the fixed-code check.
const Bytes kCheck{0x00, 0x01, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x38};
// Conversion table <通常運転モード>, rows 01 (stop), 00 (reset & stop), 40 (1149 rpm),
// 1C (504 rpm); <連続運転モード> row 40.
const Bytes kRunStop{0x00, 0x01, 0x10, 0x02, 0x01, 0x01, 0x00, 0x40};
const Bytes kRunReset{0x00, 0x01, 0x10, 0x02, 0x00, 0x01, 0x00, 0x41};
const Bytes kRun1149{0x00, 0x01, 0x10, 0x02, 0x40, 0x01, 0x00, 0x01};
const Bytes kRun504{0x00, 0x01, 0x10, 0x02, 0x1C, 0x01, 0x00, 0x25};
const Bytes kRun1149Continuous{0x00, 0x01, 0x10, 0x02, 0x40, 0xFF, 0x00, 0x03};

Options options(std::string mode = "normal", std::int64_t keepalive = 1000,
                std::int64_t master = 0) {
  return Options({{kOptMasterAddress, OptionValue{master}},
                  {kOptMode, OptionValue{std::move(mode)}},
                  {kOptKeepalive, OptionValue{keepalive}}});
}

struct Rig {
  explicit Rig(Options o = options(), Millis poll = 500ms, std::uint32_t address = 1) {
    std::string error;
    const auto cfg = make_config(address, o, error);
    EXPECT_TRUE(cfg.has_value()) << error;
    driver = std::make_unique<MDriver>(*cfg, poll);
    sim = std::make_unique<MSimulator>(cfg->device);
    bus = std::make_unique<test::Loopback>(*driver, *sim);
  }
  TimePoint now() const { return bus->now(); }
  std::int64_t value(Pt p) const {
    return std::get<std::int64_t>(driver->values()[static_cast<std::size_t>(p)]);
  }
  std::size_t count(const Bytes& frame) const {
    return static_cast<std::size_t>(std::count(bus->sent.begin(), bus->sent.end(), frame));
  }
  // Starts up and waits for the first status.
  void start() {
    ASSERT_TRUE(bus->run_until([this] { return driver->common().ready; }, 2s));
    bus->run_for(100ms);
  }
  std::unique_ptr<MDriver> driver;
  std::unique_ptr<MSimulator> sim;
  std::unique_ptr<test::Loopback> bus;
};

TEST(MdriverDriver, StartsWithTheFixedCodeCheckThenPollsWithTheStopCode) {
  Rig r;
  EXPECT_FALSE(r.driver->common().ready);
  r.start();
  ASSERT_GE(r.bus->sent.size(), 2u);
  EXPECT_EQ(r.bus->sent[0], kCheck);
  EXPECT_EQ(r.bus->sent[1], kRunStop);
  EXPECT_TRUE(r.driver->common().ready);
  EXPECT_EQ(r.value(Pt::fixed_code_state), 1);
  EXPECT_EQ(r.value(Pt::ipm_temperature), 26);  // simulator's default, the document's [1a]
  EXPECT_EQ(r.value(Pt::target_code), 0x01);
  EXPECT_EQ(r.value(Pt::sent_code), 0x01);
  EXPECT_FALSE(r.driver->common().running);
  EXPECT_TRUE(r.driver->common().faults.empty());
  EXPECT_EQ(r.driver->points().size(), r.driver->values().size());
}

TEST(MdriverDriver, ChecksUntilAnsweredAfterSilence) {
  Rig r;
  r.sim->control("silent on", r.now());
  r.bus->run_for(3s);
  for (const auto& f : r.bus->sent) EXPECT_EQ(f, kCheck);  // nothing but the check
  EXPECT_GE(r.bus->sent.size(), 6u);
  EXPECT_FALSE(r.driver->common().ready);
  r.sim->control("silent off", r.now());
  r.start();
  EXPECT_EQ(r.bus->sent.back(), kRunStop);
}

TEST(MdriverDriver, RunCommandIsTheKeepAliveAtTheShorterOfPollAndKeepAlive) {
  Rig slow(options("normal", 1000), 5000ms);  // keep-alive rules
  slow.start();
  const auto before = slow.bus->sent.size();
  slow.bus->run_for(10s);
  EXPECT_EQ(slow.bus->sent.size() - before, 10u);

  Rig fast(options("normal", 1000), 250ms);  // poll rules
  fast.start();
  const auto before2 = fast.bus->sent.size();
  fast.bus->run_for(10s);
  EXPECT_EQ(fast.bus->sent.size() - before2, 40u);

  // A gateway that keeps polling never lets the driver trip with 0x0C.
  Rig idle(options("normal", 5000), 60000ms);
  idle.start();
  idle.bus->run_for(60s);
  EXPECT_TRUE(idle.driver->common().faults.empty());
  EXPECT_NE(idle.sim->control("state", idle.now()).find("error=0x00"), std::string::npos);
}

TEST(MdriverDriver, SetpointStoredWhileStoppedThenRun1149AsCode40) {
  Rig r;
  r.start();
  EXPECT_EQ(r.driver->setpoint(1149, 1, r.now()), WriteStatus::done);
  EXPECT_EQ(r.driver->common().setpoint_rpm, 1149);
  const auto sent = r.bus->sent.size();
  r.bus->run_for(50ms);
  EXPECT_EQ(r.bus->sent.size(), sent);  // a stored setpoint costs no traffic
  EXPECT_EQ(r.driver->command(Command::run_forward, 2, r.now()), WriteStatus::pending);
  r.bus->run_for(20ms);
  ASSERT_EQ(r.bus->sent.size(), sent + 1);  // at once, not at the next poll
  EXPECT_EQ(r.bus->sent.back(), kRun1149);
  ASSERT_EQ(r.bus->completions.size(), 1u);
  EXPECT_EQ(r.bus->completions[0].ticket, 2u);
  EXPECT_EQ(r.bus->completions[0].result, WriteResult::ok);
  EXPECT_TRUE(r.driver->common().running);
  EXPECT_EQ(r.driver->common().command, Command::run_forward);
  r.bus->run_for(4s);  // 0x1C..0x40 at 20 codes/s
  EXPECT_EQ(r.driver->common().speed_rpm, 1149);
  EXPECT_EQ(r.value(Pt::actual_code), 0x40);
  EXPECT_EQ(r.value(Pt::target_rpm), 1149);
  EXPECT_EQ(r.bus->sent.back(), kRun1149);  // the keep-alive carries the target
}

TEST(MdriverDriver, ContinuousModeSendsFF) {
  Rig r(options("continuous"));
  r.start();
  r.driver->setpoint(1149, 1, r.now());
  r.driver->command(Command::run_forward, 2, r.now());
  r.bus->run_for(20ms);
  EXPECT_EQ(r.bus->sent.back(), kRun1149Continuous);
}

TEST(MdriverDriver, SetpointWhileRunningIsSentAtOnceAndConfirmedByTheEcho) {
  Rig r;
  r.start();
  r.driver->setpoint(1149, 1, r.now());
  r.driver->command(Command::run_forward, 2, r.now());
  r.bus->run_for(1s);
  EXPECT_EQ(r.driver->setpoint(504, 3, r.now()), WriteStatus::pending);
  r.bus->run_for(20ms);
  EXPECT_EQ(r.bus->sent.back(), kRun504);
  ASSERT_EQ(r.bus->completions.size(), 2u);
  EXPECT_EQ(r.bus->completions[1].ticket, 3u);
  EXPECT_EQ(r.bus->completions[1].result, WriteResult::ok);
  EXPECT_EQ(r.driver->common().setpoint_rpm, 504);
}

TEST(MdriverDriver, SetpointRangeAndNearestEntry) {
  Rig r;
  r.start();
  EXPECT_EQ(r.driver->setpoint(503, 1, r.now()), WriteStatus::invalid_value);
  EXPECT_EQ(r.driver->setpoint(0, 1, r.now()), WriteStatus::invalid_value);
  EXPECT_EQ(r.driver->setpoint(2857, 1, r.now()), WriteStatus::invalid_value);
  EXPECT_EQ(r.driver->setpoint(2856, 1, r.now()), WriteStatus::done);
  EXPECT_EQ(r.driver->setpoint(1160, 1, r.now()), WriteStatus::done);
  EXPECT_EQ(r.driver->common().setpoint_rpm, 1167);
}

TEST(MdriverDriver, StopQuickStopAndReverse) {
  Rig r;
  r.start();
  r.driver->setpoint(1149, 1, r.now());
  r.driver->command(Command::run_forward, 2, r.now());
  r.bus->run_for(1s);
  EXPECT_EQ(r.driver->command(Command::run_reverse, 3, r.now()), WriteStatus::invalid_value);
  EXPECT_EQ(r.driver->command(Command::quick_stop, 4, r.now()), WriteStatus::pending);
  r.bus->run_for(20ms);
  EXPECT_EQ(r.bus->sent.back(), kRunStop);
  EXPECT_EQ(r.bus->completions.back().ticket, 4u);
  EXPECT_EQ(r.bus->completions.back().result, WriteResult::ok);
  EXPECT_EQ(r.driver->command(Command::stop, 5, r.now()), WriteStatus::pending);
  r.bus->run_for(3s);
  EXPECT_EQ(r.bus->sent.back(), kRunStop);
  EXPECT_FALSE(r.driver->common().running);
  EXPECT_EQ(r.driver->common().speed_rpm, 0);
  EXPECT_EQ(r.count(kRunReset), 0u);  // a plain stop never resets errors
}

TEST(MdriverDriver, RefusedBeforeReadyAndWithoutSetpoint) {
  Rig r;
  EXPECT_EQ(r.driver->command(Command::stop, 1, r.now()), WriteStatus::refused);
  EXPECT_EQ(r.driver->setpoint(1149, 2, r.now()), WriteStatus::done);  // stored for later
  r.start();
  Rig fresh;
  fresh.start();
  EXPECT_EQ(fresh.driver->command(Command::run_forward, 3, fresh.now()), WriteStatus::refused);
  EXPECT_EQ(fresh.driver->write(0, Value{std::int64_t{1}}, 4, fresh.now()),
            WriteStatus::invalid_value);
}

TEST(MdriverDriver, OverTemperatureTripAndResetFault) {
  Rig r;
  r.start();
  r.driver->setpoint(1149, 1, r.now());
  r.driver->command(Command::run_forward, 2, r.now());
  r.bus->run_for(3s);
  r.sim->control("fault ipm_over_temperature", r.now());
  r.bus->run_for(1s);
  const CommonState& c = r.driver->common();
  EXPECT_TRUE(c.faults.has(Fault::drive_over_temperature));
  EXPECT_EQ(most_severe(c.faults), Fault::drive_over_temperature);
  EXPECT_EQ(c.native_fault, 0x0Eu);
  EXPECT_EQ(r.value(Pt::error_code), 0x0E);
  EXPECT_FALSE(c.running);
  EXPECT_EQ(c.speed_rpm, 0);
  // Latched: a run command would not run.
  EXPECT_EQ(r.driver->command(Command::run_forward, 3, r.now()), WriteStatus::refused);
  EXPECT_EQ(r.driver->command(Command::reset_fault, 4, r.now()), WriteStatus::pending);
  r.bus->run_for(20ms);
  EXPECT_EQ(r.bus->sent.back(), kRunReset);
  EXPECT_EQ(r.bus->completions.back().ticket, 4u);
  EXPECT_EQ(r.bus->completions.back().result, WriteResult::ok);
  EXPECT_TRUE(c.faults.empty());
  EXPECT_EQ(c.native_fault, 0u);
  EXPECT_EQ(c.command, Command::stop);
  r.bus->run_for(1s);
  EXPECT_EQ(r.bus->sent.back(), kRunStop);  // reset once, then the plain stop code
  EXPECT_EQ(r.count(kRunReset), 1u);
  EXPECT_EQ(r.driver->command(Command::run_forward, 5, r.now()), WriteStatus::pending);
  r.bus->run_for(20ms);
  EXPECT_EQ(r.bus->sent.back(), kRun1149);
}

TEST(MdriverDriver, EveryErrorCodeMapsIntoFaultsAndNativeFault) {
  Rig r;
  r.start();
  for (const auto& e : error_codes()) {
    SCOPED_TRACE(std::string(e.name));
    r.sim->control("fault " + std::to_string(e.code), r.now());
    r.bus->run_for(600ms);
    FaultSet want;
    want.set(e.fault);
    EXPECT_EQ(r.driver->common().faults, want);
    EXPECT_EQ(r.driver->common().native_fault, e.code);
    r.driver->command(Command::reset_fault, 1, r.now());
    r.bus->run_for(600ms);
    EXPECT_TRUE(r.driver->common().faults.empty());
  }
}

TEST(MdriverDriver, FixedCodeErrorIsAHardwareFaultAndNotReady) {
  Rig r;
  r.sim->control("eeprom fail", r.now());
  r.bus->run_for(3s);
  EXPECT_FALSE(r.driver->common().ready);
  EXPECT_TRUE(r.driver->common().faults.has(Fault::hardware_fault));
  EXPECT_EQ(r.driver->common().native_fault, kNativeFixedCodeError);
  EXPECT_EQ(r.value(Pt::fixed_code_state), 2);
  for (const auto& f : r.bus->sent) EXPECT_EQ(f, kCheck);  // no run data while the code fails
  EXPECT_EQ(r.driver->command(Command::stop, 1, r.now()), WriteStatus::refused);
  r.sim->control("eeprom ok", r.now());
  r.start();
  EXPECT_TRUE(r.driver->common().faults.empty());
  EXPECT_EQ(r.bus->sent.back(), kRunStop);
}

TEST(MdriverDriver, BadChecksumIsResentIdentically) {
  Rig r;
  r.start();
  r.sim->control("corrupt 1", r.now());
  r.driver->setpoint(1149, 1, r.now());
  r.driver->command(Command::run_forward, 2, r.now());
  r.bus->run_for(20ms);
  EXPECT_EQ(r.bus->bad_frames, 1);
  EXPECT_EQ(r.bus->retries, 1);
  const auto n = r.bus->sent.size();
  EXPECT_EQ(r.bus->sent[n - 1], kRun1149);
  EXPECT_EQ(r.bus->sent[n - 2], kRun1149);
  ASSERT_FALSE(r.bus->completions.empty());
  EXPECT_EQ(r.bus->completions.back().result, WriteResult::ok);
}

TEST(MdriverDriver, NoReplyFailsTheWriteThenCommLostRedoesTheCheck) {
  Rig r;
  r.start();
  r.sim->control("silent on", r.now());
  r.driver->setpoint(1149, 1, r.now());
  EXPECT_EQ(r.driver->command(Command::run_forward, 2, r.now()), WriteStatus::pending);
  r.bus->run_for(1s);
  ASSERT_EQ(r.bus->completions.size(), 1u);
  EXPECT_EQ(r.bus->completions[0].result, WriteResult::no_response);
  EXPECT_EQ(r.bus->sent.back(), kRun1149);
  EXPECT_EQ(r.bus->retries % 2, 0);  // kAttempts = 3: two resends a turn
  EXPECT_GE(r.bus->retries, 2);
  r.bus->run_for(6s);
  EXPECT_TRUE(r.bus->comm_lost());
  EXPECT_FALSE(r.driver->common().ready);
  EXPECT_EQ(r.bus->sent.back(), kCheck);
  r.sim->control("silent off", r.now());
  r.start();
  EXPECT_FALSE(r.bus->comm_lost());
  // The command in force survives: the keep-alive carries the setpoint again.
  EXPECT_EQ(r.bus->sent.back(), kRun1149);
}

TEST(MdriverDriver, CommLostFailsPendingWrites) {
  Rig r;
  r.start();
  r.driver->command(Command::stop, 7, r.now());
  r.driver->on_comm_lost(r.now());
  std::vector<Completion> out;
  r.driver->take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].ticket, 7u);
  EXPECT_EQ(out[0].result, WriteResult::no_response);
  EXPECT_FALSE(r.driver->common().ready);
  const auto ex = r.driver->next_exchange(r.now());
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, kCheck);
}

TEST(MdriverDriver, PowerCycledDriverIsCheckedAgain) {
  Rig r;
  r.start();
  r.sim->control("power-cycle", r.now());  // forgets the check: ignores run data
  r.bus->run_for(8s);
  EXPECT_TRUE(r.driver->common().ready);
  EXPECT_EQ(r.count(kCheck), 2u);
}

TEST(MdriverDriver, RejectsForeignNoiseAndStaleFrames) {
  Rig r;
  auto ex = r.driver->next_exchange(r.now());
  ASSERT_TRUE(ex.has_value());
  // Another driver's echo: foreign.
  const Wire other = encode_check_reply(0x02, 0x00, kFixedCode);
  auto v = r.driver->on_receive(other, r.now());
  EXPECT_EQ(v.kind, RxKind::foreign);
  EXPECT_EQ(v.consumed, other.size());
  // The master's own frame heard back (not from the driver): foreign.
  v = r.driver->on_receive(kCheck, r.now());
  EXPECT_EQ(v.kind, RxKind::foreign);
  // A run reply while the check is awaited: foreign (stale).
  RunReply rr;
  const Wire run = encode_run_reply(0x01, 0x00, rr);
  v = r.driver->on_receive(run, r.now());
  EXPECT_EQ(v.kind, RxKind::foreign);
  // Noise.
  const Bytes noise{0xFF, 0xFF, 0x33};
  v = r.driver->on_receive(noise, r.now());
  EXPECT_EQ(v.kind, RxKind::noise);
  EXPECT_GT(v.consumed, 0u);
  // Bad checksum.
  Wire bad = encode_check_reply(0x01, 0x00, kFixedCode);
  bad.back() ^= 1;
  v = r.driver->on_receive(bad, r.now());
  EXPECT_EQ(v.kind, RxKind::bad_checksum);
  EXPECT_EQ(v.consumed, bad.size());
  // Half a frame: incomplete.
  const Wire good = encode_check_reply(0x01, 0x00, kFixedCode);
  v = r.driver->on_receive(ByteView(good).first(4), r.now());
  EXPECT_EQ(v.kind, RxKind::incomplete);
  v = r.driver->on_receive(good, r.now());
  EXPECT_EQ(v.kind, RxKind::reply);
  EXPECT_TRUE(r.driver->common().ready);
}

TEST(MdriverDriver, ConfigurableAddresses) {
  Rig r(options("normal", 1000, 0x10), 500ms, 0x22);
  r.start();
  EXPECT_EQ(r.bus->sent[0], (Bytes{0x10, 0x22, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x07}));
  EXPECT_TRUE(r.driver->common().ready);
  std::string error;
  EXPECT_FALSE(make_config(0x10, options("normal", 1000, 0x10), error).has_value());
  EXPECT_FALSE(error.empty());
  EXPECT_FALSE(make_config(0x100, options(), error).has_value());
}

TEST(MdriverDriver, AnEchoOfAnotherCodeRefusesTheWrite) {
  Rig r;
  r.start();
  ASSERT_EQ(r.driver->command(Command::stop, 9, r.now()), WriteStatus::pending);
  const auto ex = r.driver->next_exchange(r.now());
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, kRunStop);
  EXPECT_EQ(ex->priority, Priority::command);
  RunReply rr;
  rr.target_code = 0x05;  // not the D4 sent
  const auto v = r.driver->on_receive(encode_run_reply(0x01, 0x00, rr), r.now());
  EXPECT_EQ(v.kind, RxKind::reply);
  std::vector<Completion> out;
  r.driver->take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].ticket, 9u);
  EXPECT_EQ(out[0].result, WriteResult::refused);
}

TEST(MdriverDriver, UnconfirmedWritesExpireAndSupersededOnesFail) {
  Rig r;
  r.start();
  r.driver->setpoint(1149, 1, r.now());
  ASSERT_EQ(r.driver->command(Command::run_forward, 2, r.now()), WriteStatus::pending);
  ASSERT_EQ(r.driver->command(Command::stop, 3, r.now()), WriteStatus::pending);
  const auto ex = r.driver->next_exchange(r.now());
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, kRunStop);  // the later write wins
  std::vector<Completion> out;
  r.driver->take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].ticket, 2u);
  EXPECT_EQ(out[0].result, WriteResult::no_response);
  // No reply and no on_no_reply: the driver's own deadline fails it.
  EXPECT_LE(r.driver->wake_at(), r.now() + kConfirmDeadline);
  r.driver->next_exchange(r.now() + kConfirmDeadline);
  out.clear();
  r.driver->take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].ticket, 3u);
  EXPECT_EQ(out[0].result, WriteResult::no_response);
}

TEST(MdriverDriver, TraitsAndExchangeShape) {
  Rig r;
  EXPECT_EQ(r.driver->traits().comm_timeout, 6000ms);
  const auto ex = r.driver->next_exchange(r.now());
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->reply, ReplyMode::expected);
  EXPECT_EQ(ex->priority, Priority::poll);
  EXPECT_EQ(ex->attempts, kAttempts);
  EXPECT_FALSE(r.driver->next_exchange(r.now()).has_value());  // one at a time
}

}  // namespace
}  // namespace drivegate::mdriver
