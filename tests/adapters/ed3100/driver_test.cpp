// The driver against the simulator on simulated time (tests/support/loopback.h): exact frames
// on the wire, completions, fault mapping and comm_lost recovery.
#include "driver.h"

#include <gtest/gtest.h>

#include "loopback.h"
#include "points.h"
#include "registers.h"
#include "simulator.h"
#include "test_options.h"

namespace drivegate::ed3100 {
namespace {

using B = Bytes;

// Document frames (see codec_test.cpp for their sections).
const B kReadParam = {0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5};
const B kWriteParam = {0x1F, 0x06, 0x00, 0x06, 0x13, 0x88, 0x67, 0x23};
const B kReadMonitor = {0x1F, 0x03, 0x0D, 0x00, 0x00, 0x00, 0x44, 0xD8};
const B kReadFault = {0x1F, 0x03, 0x0E, 0x01, 0x00, 0x00, 0x15, 0x5C};
const B kForward = {0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04, 0x00, 0x1E, 0x10, 0x88, 0x67, 0xE6};
const B kReverse = {0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04, 0x00, 0x2E, 0x10, 0x88, 0x67, 0xE9};
const B kStop = {0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74};

class DriverTest : public ::testing::Test {
 protected:
  explicit DriverTest(std::vector<std::string> params = {"00-06"}, std::uint8_t address = 0x1F)
      : config(*make_config(address, test::options({{"parameters", params}}), error)),
        driver(config, Millis(500)),
        sim(address, ReadForm::document),
        bus(driver, sim) {}

  bool until(const std::function<bool()>& f, Millis limit = Millis(5000)) {
    return bus.run_until(f, limit);
  }
  bool completed(Ticket t, WriteResult r) {
    for (const Completion& c : bus.completions) {
      if (c.ticket == t) return c.result == r;
    }
    return false;
  }
  bool done(Ticket t) {
    return std::any_of(bus.completions.begin(), bus.completions.end(),
                       [&](const Completion& c) { return c.ticket == t; });
  }
  // Frames sent from index `from` on.
  std::vector<B> sent_from(std::size_t from) {
    return {bus.sent.begin() + static_cast<long>(from), bus.sent.end()};
  }
  const Value& value(std::size_t i) { return driver.values().at(i); }
  std::size_t param(std::size_t p) { return parameter_index(config, p); }

  void start() {
    ASSERT_TRUE(until([&] { return driver.common().ready; }));
  }
  // Writes 42.32 Hz, the document examples' reference, while stopped (stored: no traffic).
  void doc_reference() {
    ASSERT_EQ(driver.write(index(Fixed::frequency_setpoint), 42.32, 99, bus.now()),
              WriteStatus::done);
  }

  std::string error;
  Config config;
  Ed3100Driver driver;
  Ed3100Simulator sim;
  drivegate::test::Loopback bus;
};

TEST_F(DriverTest, TraitsFromOptions) {
  EXPECT_EQ(driver.traits().inter_frame_gap, Millis(10));  // document: >= 10 ms silence
  EXPECT_EQ(driver.traits().comm_timeout, Millis(3000));
}

TEST_F(DriverTest, StartupReadsParametersThenPollsStatusAndMonitors) {
  start();
  // The start-up read of 00-06 is the document's own frame; then 0x0E01 and the monitors,
  // sent with 00 00 as the document prints them.
  ASSERT_GE(bus.sent.size(), 2u);
  EXPECT_EQ(bus.sent[0], kReadParam);
  EXPECT_EQ(bus.sent[1], kReadFault);
  ASSERT_TRUE(until([&] { return bus.sent.size() >= 6; }));
  EXPECT_EQ(bus.sent[2], kReadMonitor);
  EXPECT_EQ(bus.sent[3], encode_read(0x1F, 0x0D01, 0));
  EXPECT_EQ(bus.sent[4], encode_read(0x1F, 0x0D02, 0));
  EXPECT_EQ(bus.sent[5], encode_read(0x1F, 0x0D03, 0));
  EXPECT_EQ(bus.retries, 0);

  EXPECT_EQ(value(param(0)), Value(std::int64_t{0x1088}));
  EXPECT_EQ(value(monitor_value_index(0) + 1), Value(std::int64_t{0x1084}));
  EXPECT_EQ(value(monitor_value_index(0) + 2), Value(std::int64_t{0x4148}));
  EXPECT_NEAR(as_double(value(monitor_value_index(0))), 42.28, 1e-9);  // "42.28 Hz, stopped"
  EXPECT_NEAR(as_double(value(monitor_value_index(3))), 537.0, 1e-9);
  EXPECT_EQ(value(index(Fixed::fault_code)), Value(std::int64_t{0xFFFF}));
  EXPECT_EQ(value(index(Fixed::state_word)), Value(std::int64_t{0x0148}));
  EXPECT_EQ(value(index(Fixed::commanded_direction)), Value(std::int64_t{1}));
  EXPECT_EQ(value(index(Fixed::running)), Value(std::int64_t{0}));
  const CommonState& c = driver.common();
  EXPECT_EQ(c.speed_rpm, 0);  // the stopped bit: 42.28 is the reference on display
  EXPECT_FALSE(c.running);
  EXPECT_TRUE(c.faults.empty());
  EXPECT_EQ(c.native_fault, 0u);

  // The next cycle, 500 ms on, does not read the parameter again.
  const std::size_t n = bus.sent.size();
  bus.run_for(Millis(520));
  const auto next = sent_from(n);
  ASSERT_EQ(next.size(), 5u);
  EXPECT_EQ(next[0], kReadFault);
  EXPECT_EQ(next[1], kReadMonitor);
}

TEST_F(DriverTest, RunForwardAndReverseSendTheDocumentFrames) {
  start();
  doc_reference();
  EXPECT_EQ(driver.common().setpoint_rpm, 1270);  // 42.32 Hz x 120 / 4
  std::size_t n = bus.sent.size();
  ASSERT_EQ(driver.command(Command::run_forward, 1, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(1); }));
  EXPECT_TRUE(completed(1, WriteResult::ok));
  EXPECT_EQ(bus.sent.at(n), kForward);
  EXPECT_EQ(driver.common().command, Command::run_forward);
  ASSERT_TRUE(until([&] { return driver.common().speed_rpm == 1270; }));
  EXPECT_TRUE(driver.common().running);

  n = bus.sent.size();
  ASSERT_EQ(driver.command(Command::run_reverse, 2, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(2); }));
  EXPECT_TRUE(completed(2, WriteResult::ok));
  EXPECT_EQ(bus.sent.at(n), kReverse);
  ASSERT_TRUE(until([&] { return driver.common().speed_rpm == -1270; }));
  EXPECT_EQ(value(index(Fixed::direction)), Value(std::int64_t{1}));

  n = bus.sent.size();
  ASSERT_EQ(driver.command(Command::stop, 3, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(3); }));
  EXPECT_TRUE(completed(3, WriteResult::ok));
  EXPECT_EQ(bus.sent.at(n), kStop);
  ASSERT_TRUE(until([&] { return !driver.common().running; }));
  EXPECT_EQ(driver.common().speed_rpm, 0);
}

TEST_F(DriverTest, QuickStopIsThePlainStop) {
  start();
  const std::size_t n = bus.sent.size();
  ASSERT_EQ(driver.command(Command::quick_stop, 1, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(1); }));
  EXPECT_EQ(bus.sent.at(n), kStop);
}

TEST_F(DriverTest, SetpointStoredWhileStoppedSentWhileRunning) {
  start();
  std::size_t n = bus.sent.size();
  EXPECT_EQ(driver.setpoint(1500, 1, bus.now()), WriteStatus::done);  // 50.00 Hz at 4 poles
  EXPECT_EQ(driver.setpoint(-1, 2, bus.now()), WriteStatus::invalid_value);
  EXPECT_NEAR(as_double(value(index(Fixed::frequency_setpoint))), 50.0, 1e-9);
  ASSERT_EQ(driver.command(Command::run_forward, 3, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(3); }));
  EXPECT_EQ(bus.sent.at(n),
            encode_write_multiple(0x1F, 0x2000, std::vector<std::uint16_t>{kCmdForward, 0x1388}));
  n = bus.sent.size();
  ASSERT_EQ(driver.setpoint(900, 4, bus.now()), WriteStatus::pending);  // 30.00 Hz
  ASSERT_TRUE(until([&] { return done(4); }));
  EXPECT_TRUE(completed(4, WriteResult::ok));
  EXPECT_EQ(bus.sent.at(n), encode_write_single(0x1F, kRegFrequency, 3000));
  ASSERT_TRUE(until([&] { return driver.common().speed_rpm == 900; }));
}

TEST_F(DriverTest, ParameterWriteIsSentWith06AndReadBack) {
  start();
  const std::size_t n = bus.sent.size();
  ASSERT_EQ(driver.write(param(0), std::int64_t{5000}, 7, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(7) && bus.sent.size() >= n + 2; }));
  EXPECT_TRUE(completed(7, WriteResult::ok));
  EXPECT_EQ(bus.sent[n], kWriteParam);  // the document's 06 example
  EXPECT_EQ(bus.sent[n + 1], kReadParam);
  EXPECT_EQ(value(param(0)), Value(std::int64_t{5000}));
  EXPECT_EQ(driver.write(param(0), std::string("x"), 8, bus.now()), WriteStatus::invalid_value);
  EXPECT_EQ(driver.write(index(Fixed::fault_code), std::int64_t{1}, 9, bus.now()),
            WriteStatus::invalid_value);
}

TEST_F(DriverTest, ExceptionRefusesAndFaultsMapToOther) {
  start();
  // The drive trips before the driver has polled it: its exception refuses the run.
  sim.control("fault 0x12", bus.now());
  ASSERT_EQ(driver.command(Command::run_forward, 1, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(1); }));
  EXPECT_TRUE(completed(1, WriteResult::refused));
  EXPECT_EQ(bus.retries, 0);
  ASSERT_TRUE(until([&] { return !driver.common().faults.empty(); }));
  EXPECT_TRUE(driver.common().faults.has(Fault::other));
  EXPECT_EQ(driver.common().native_fault, 0x12u);
  EXPECT_EQ(value(index(Fixed::fault_code)), Value(std::int64_t{0x12}));
  // Known tripped: refused locally.
  EXPECT_EQ(driver.command(Command::run_reverse, 2, bus.now()), WriteStatus::refused);

  const std::size_t n = bus.sent.size();
  ASSERT_EQ(driver.command(Command::reset_fault, 3, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(3); }));
  EXPECT_TRUE(completed(3, WriteResult::ok));
  EXPECT_EQ(bus.sent.at(n), encode_write_single(0x1F, 0x2002, 0x0002));
  ASSERT_TRUE(until([&] { return driver.common().faults.empty(); }));
  EXPECT_EQ(driver.common().native_fault, 0u);
}

TEST_F(DriverTest, BadChecksumIsResentIdentically) {
  start();
  sim.control("corrupt 1", bus.now());
  const std::size_t n = bus.sent.size();
  bus.run_for(Millis(600));
  ASSERT_GE(bus.sent.size(), n + 2);
  EXPECT_EQ(bus.sent[n], kReadMonitor);  // start() returns with the monitors still queued
  EXPECT_EQ(bus.sent[n + 1], kReadMonitor);
  EXPECT_EQ(bus.bad_frames, 1);
  EXPECT_EQ(bus.retries, 1);
}

TEST_F(DriverTest, SilenceFailsWritesThenCommLostThenStartupAgain) {
  start();
  sim.control("silent on", bus.now());
  const std::size_t n = bus.sent.size();
  ASSERT_EQ(driver.command(Command::stop, 1, bus.now()), WriteStatus::pending);
  ASSERT_TRUE(until([&] { return done(1); }));
  EXPECT_TRUE(completed(1, WriteResult::no_response));
  EXPECT_EQ(sent_from(n), (std::vector<B>{kStop, kStop, kStop}));  // attempts = 3
  ASSERT_TRUE(until([&] { return bus.comm_lost(); }));
  EXPECT_FALSE(driver.common().ready);

  sim.control("silent off", bus.now());
  const std::size_t m = bus.sent.size();
  ASSERT_TRUE(until([&] { return driver.common().ready; }));
  // The start-up sequence again: the parameter before the status.
  const auto after = sent_from(m);
  const auto first_param = std::find(after.begin(), after.end(), kReadParam);
  const auto first_fault = std::find(after.begin(), after.end(), kReadFault);
  ASSERT_NE(first_param, after.end());
  EXPECT_LT(first_param - after.begin(), first_fault - after.begin());
}

TEST_F(DriverTest, CommLostFailsQueuedWrites) {
  start();
  ASSERT_EQ(driver.command(Command::stop, 1, bus.now()), WriteStatus::pending);
  driver.on_comm_lost(bus.now());
  std::vector<Completion> out;
  driver.take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].result, WriteResult::no_response);
  EXPECT_FALSE(driver.common().ready);
}

TEST_F(DriverTest, StandardFormRepliesAreAccepted) {
  sim.control("form standard", bus.now());
  start();
  EXPECT_EQ(value(param(0)), Value(std::int64_t{0x1088}));
  ASSERT_TRUE(until(
      [&] { return !std::holds_alternative<std::monostate>(value(monitor_value_index(0))); }));
  EXPECT_NEAR(as_double(value(monitor_value_index(0))), 42.28, 1e-9);
  EXPECT_EQ(bus.retries, 0);
}

TEST_F(DriverTest, NoiseAndForeignFramesAreSkipped) {
  const Bytes foreign =
      encode_read_reply(0x05, 0x0006, std::vector<std::uint16_t>{1}, ReadForm::document);
  bus.line_filter = [&](Bytes b) {
    if (b.empty()) return b;
    Bytes out = {0xAA, 0x55};
    if (b[1] == kFnRead && b[2] == 0x00) out.insert(out.end(), foreign.begin(), foreign.end());
    out.insert(out.end(), b.begin(), b.end());
    return out;
  };
  start();
  EXPECT_EQ(value(param(0)), Value(std::int64_t{0x1088}));
  EXPECT_EQ(bus.retries, 0);
  EXPECT_EQ(bus.bad_frames, 0);
}

TEST_F(DriverTest, VerdictsAlwaysConsume) {
  // Nothing on the line awaited: bytes are noise, never consumed == 0.
  const Bytes junk = {0x00};
  const RxVerdict v = driver.on_receive(junk, bus.now());
  EXPECT_EQ(v.kind, RxKind::noise);
  EXPECT_EQ(v.consumed, 1u);
  // A reply for another register is foreign.
  ASSERT_TRUE(driver.next_exchange(bus.now()));  // the parameter read
  const Bytes other =
      encode_read_reply(0x1F, 0x0007, std::vector<std::uint16_t>{1}, ReadForm::document);
  EXPECT_EQ(driver.on_receive(other, bus.now()).kind, RxKind::foreign);
  const Bytes right =
      encode_read_reply(0x1F, 0x0006, std::vector<std::uint16_t>{1}, ReadForm::document);
  EXPECT_EQ(driver.on_receive(right, bus.now()).kind, RxKind::reply);
}

class BroadcastTest : public DriverTest {
 protected:
  BroadcastTest() : DriverTest({}, 0x00) {}
};

TEST_F(BroadcastTest, WritesGoOutUnansweredAndNothingIsPolled) {
  EXPECT_FALSE(driver.next_exchange(bus.now()));
  ASSERT_EQ(driver.command(Command::stop, 1, bus.now()), WriteStatus::pending);
  const auto ex = driver.next_exchange(bus.now());
  ASSERT_TRUE(ex);
  EXPECT_EQ(ex->reply, ReplyMode::none);
  EXPECT_EQ(ex->priority, Priority::command);
  EXPECT_EQ(ex->frame, encode_write_single(0x00, 0x2000, 0x0001));
  std::vector<Completion> out;
  driver.take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].result, WriteResult::ok);
  EXPECT_FALSE(driver.next_exchange(bus.now()));
}

}  // namespace
}  // namespace drivegate::ed3100
