// The driver alone, where the contract of include/drivegate/driver.h is about one call: check()
// judging a request part by part before anything is applied, with no side effect, and exactly as
// apply() then takes its parts.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "adapter_factories.h"
#include "bench.h"
#include "driver_by_hand.h"
#include "write_contract.h"

namespace drivegate::ed3100 {
namespace {

using test::WriteContract;

// check() judges a request before anything is applied, with no side effect.
TEST(Ed3100Check, JudgesEveryPartAndTouchesNothing) {
  const auto driver =
      test::make_driver(drivegate_adapter, {.options = kWithParameter, .address = 0x1F});
  ASSERT_TRUE(driver);
  const auto& points = driver->points();
  const auto index = [&](std::string_view name) {
    return static_cast<std::size_t>(
        std::find_if(points.begin(), points.end(),
                     [&](const PointSpec& p) { return p.name == name; }) -
        points.begin());
  };
  const auto one = [&](WriteOp op) { return driver->check(std::vector<WriteOp>{std::move(op)}); };

  EXPECT_EQ(one(WriteOp::of_point(index("frequency_setpoint"), 42.32)), WriteCheck::ok);
  EXPECT_EQ(one(WriteOp::of_point(index("frequency_setpoint"), std::string("x"))),
            WriteCheck::invalid_value);
  EXPECT_EQ(one(WriteOp::of_point(index("frequency_setpoint"), Value{})),
            WriteCheck::invalid_value);
  EXPECT_EQ(one(WriteOp::of_point(index("param_00_06"), std::int64_t{5000})), WriteCheck::ok);
  EXPECT_EQ(one(WriteOp::of_point(index("param_00_06"), 70000.0)), WriteCheck::invalid_value);
  EXPECT_EQ(one(WriteOp::of_point(index("state_word"), std::int64_t{1})),
            WriteCheck::invalid_value);
  EXPECT_EQ(one(WriteOp::of_setpoint(-1)), WriteCheck::invalid_value);
  EXPECT_EQ(one(WriteOp::of_setpoint(19660)), WriteCheck::ok);             // 655.33 Hz at 4 poles
  EXPECT_EQ(one(WriteOp::of_setpoint(19661)), WriteCheck::invalid_value);  // past 0xFFFF
  for (const Command c : kAllCommands) EXPECT_EQ(one(WriteOp::of_command(c)), WriteCheck::ok);
  EXPECT_EQ(driver->check(std::vector<WriteOp>{WriteOp::of_setpoint(1500),
                                               WriteOp::of_command(Command::run_forward)}),
            WriteCheck::ok);
  EXPECT_EQ(
      driver->check(std::vector<WriteOp>{WriteOp::of_setpoint(1500), WriteOp::of_setpoint(-1)}),
      WriteCheck::invalid_value);

  // Nothing was applied: no setpoint, no command, nothing waiting for the line.
  EXPECT_EQ(driver->common().setpoint_rpm, 0);
  EXPECT_EQ(driver->common().command, Command::stop);
  EXPECT_EQ(as_double(driver->values().at(index("frequency_setpoint"))), 0.0);
  const auto first = driver->next_exchange(TimePoint{} + std::chrono::hours(1));
  ASSERT_TRUE(first);
  EXPECT_EQ(first->frame, kReadParam);
}

// A driver from the adapter's own factory, and the drive played by the adapter's own simulator,
// frame by frame without a line: what it answers goes straight back, what it leaves unanswered
// is an exchange without a reply. Time passes, and the simulator ticks, while nothing is due.
struct Hand : test::DriverByHand {
  Hand()
      : DriverByHand(
            test::make_driver(drivegate_adapter, {.options = kWithParameter, .address = 0x1F})),
        drive(test::make_simulator(drivegate_adapter, 0x1F, kWithParameter)) {}

  bool turn() override {
    const auto ex = d->next_exchange(now);
    if (!ex) {
      now += 10ms;
      (void)drive->on_tick(now);
      return true;
    }
    sent.push_back(ex->frame);
    now += 20ms;
    const Bytes reply = drive->on_receive(ex->frame, now);
    if (ex->reply == ReplyMode::none) return true;
    if (reply.empty() || d->on_receive(reply, now).kind != RxKind::reply) d->on_no_reply(now);
    return true;
  }
  // The start-up reads are in.
  void ready() {
    for (int i = 0; i < 50 && !d->common().ready; ++i) turn();
    ASSERT_TRUE(d->common().ready);
  }

  std::unique_ptr<Simulator> drive;
};

// The states a request may find the driver in.
enum class State { not_ready, stopped, stored, running, tripped, locked };

void bring(Hand& h, State s) {
  if (s == State::not_ready) return;
  h.ready();
  if (s == State::stopped) return;
  if (s == State::tripped) {
    ASSERT_EQ(h.drive->control("fault 0x12", h.now), "ok fault=0x0012");
    for (int i = 0; i < 100 && h.d->common().faults.empty(); ++i) h.turn();
    ASSERT_FALSE(h.d->common().faults.empty());
    return;
  }
  if (s == State::locked) {
    ASSERT_EQ(h.drive->control("lock on", h.now), "ok lock=on");
    return;
  }
  ASSERT_EQ(h.apply(WriteOp::of_setpoint(1500)), WriteStatus::done);
  if (s == State::stored) return;
  ASSERT_TRUE(test::runs_forward(h));
}

std::vector<test::WriteState> states() {
  return test::write_states<Hand>(
      bring, {"not ready", "stopped", "setpoint stored", "running", "tripped", "locked"});
}

// The common block's requests, and the adapter's own holding points: the reference, a
// parameter in and out of its 16 bits, and a point only ever read.
std::vector<test::Request> requests() {
  auto out = test::command_requests({-1, 0, 900, 1500, 19660, 19661});
  const std::vector<PointSpec> points =
      test::make_driver(drivegate_adapter, {.options = kWithParameter})->points();
  const auto index = [&](std::string_view name) {
    return static_cast<std::size_t>(
        std::find_if(points.begin(), points.end(),
                     [&](const PointSpec& p) { return p.name == name; }) -
        points.begin());
  };
  out.push_back({WriteOp::of_point(index("frequency_setpoint"), 42.32)});
  out.push_back({WriteOp::of_point(index("param_00_06"), std::int64_t{5000})});
  out.push_back({WriteOp::of_point(index("param_00_06"), 70000.0)});
  out.push_back({WriteOp::of_point(index("state_word"), std::int64_t{1})});
  out.push_back({WriteOp::of_setpoint(1500),
                 WriteOp::of_point(index("param_00_06"), std::int64_t{5000}),
                 WriteOp::of_command(Command::run_forward)});
  return out;
}

// The drive refuses a write only when locked (exception 04): a verdict no driver can give in
// advance, after which the later parts are never applied.
INSTANTIATE_TEST_SUITE_P(Ed3100, WriteContract,
                         testing::Values(test::WriteContractCase{.name = "ed3100",
                                                                 .states = states,
                                                                 .requests = requests,
                                                                 .turns = 100,
                                                                 .device_refuses_in = {"locked"},
                                                                 .min_compared = 151}));

}  // namespace
}  // namespace drivegate::ed3100
