#include "write_contract.h"

#include <gtest/gtest.h>

#include <optional>

namespace drivegate::test {

namespace {

WriteCheck as_check(WriteStatus s) {
  return s == WriteStatus::invalid_value ? WriteCheck::invalid_value : WriteCheck::refused;
}

// Applies `request` as the gateway does, a part once the one before it settled, and says what
// check() should have answered; nothing when the device failed a part apply() took.
std::optional<WriteCheck> applied(DriverByHand& h, const Request& request) {
  for (const WriteOp& op : request) {
    const WriteStatus s = h.apply(op);
    if (s == WriteStatus::invalid_value || s == WriteStatus::refused) return as_check(s);
    if (s == WriteStatus::pending) {
      const auto r = h.settle(h.ticket);
      EXPECT_TRUE(r.has_value()) << "part never settled";
      if (r != WriteResult::ok) return std::nullopt;
    }
  }
  // Every part the request applied has answered, and nothing else completed meanwhile.
  EXPECT_TRUE(h.completions().empty());
  return WriteCheck::ok;
}

}  // namespace

testing::AssertionResult runs_forward(DriverByHand& h) {
  const WriteStatus s = h.apply(WriteOp::of_command(Command::run_forward));
  if (s != WriteStatus::pending) {
    return testing::AssertionFailure() << "apply said " << static_cast<int>(s) << ", not pending";
  }
  const auto r = h.settle(h.ticket);
  if (r != WriteResult::ok) {
    return testing::AssertionFailure()
           << "settled " << (r ? static_cast<int>(*r) : -1) << " (-1: never), not ok";
  }
  if (h.d->common().command != Command::run_forward) {
    return testing::AssertionFailure() << "command in force is not run_forward";
  }
  return testing::AssertionSuccess();
}

void expect_fails_at_own_deadline(DriverByHand& h, TimePoint applied, Millis deadline) {
  EXPECT_LE(h.d->wake_at(), applied + deadline);
  EXPECT_TRUE(h.completions().empty());
  (void)h.d->next_exchange(applied + deadline - Millis(1));
  EXPECT_TRUE(h.completions().empty());
  (void)h.d->next_exchange(applied + deadline);
  const auto c = h.completions();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].ticket, h.ticket);
  EXPECT_EQ(c[0].result, WriteResult::no_response);
  EXPECT_LT(deadline, h.d->traits().write_timeout);
}

ContractTally expect_check_is_apply(const std::vector<WriteState>& states,
                                    const std::vector<Request>& requests) {
  ContractTally tally;
  for (const WriteState& state : states) {
    for (const Request& request : requests) {
      const std::string what = describe(request);
      SCOPED_TRACE(state.name + ": " + what);
      const auto h = state.make();
      if (testing::Test::HasFatalFailure() || !h || !h->d) return tally;
      const Published before = published(*h->d);
      const WriteCheck verdict = h->d->check(request);
      EXPECT_EQ(h->d->check(request), verdict);
      expect_same(published(*h->d), before);
      ++tally.judged;
      if (const auto taken = applied(*h, request)) {
        EXPECT_EQ(verdict, *taken);
        ++tally.compared;
      } else {
        tally.ended_by_device.push_back({state.name, what});
      }
    }
  }
  return tally;
}

void expect_check_has_no_side_effects(const std::vector<WriteState>& states,
                                      const std::vector<Request>& requests, int turns) {
  for (const WriteState& state : states) {
    SCOPED_TRACE(state.name);
    const auto judged = state.make();
    const auto untouched = state.make();
    if (testing::Test::HasFatalFailure() || !judged->d || !untouched->d) return;
    for (const Request& request : requests) (void)judged->d->check(request);
    EXPECT_TRUE(judged->completions().empty());
    expect_same(published(*judged->d), published(*untouched->d));
    // And the line carries the same from here on.
    for (int i = 0; i < turns; ++i) {
      judged->turn();
      untouched->turn();
    }
    EXPECT_EQ(judged->sent, untouched->sent);
  }
}

std::vector<Request> command_requests(std::initializer_list<std::int32_t> setpoints) {
  std::vector<Request> out;
  for (const Command c : kAllCommands) out.push_back({WriteOp::of_command(c)});
  for (const std::int32_t rpm : setpoints) {
    out.push_back({WriteOp::of_setpoint(rpm)});
    for (const Command c : kAllCommands) {
      out.push_back({WriteOp::of_setpoint(rpm), WriteOp::of_command(c)});
    }
  }
  return out;
}

std::string describe(const Request& request) {
  std::string out;
  for (const WriteOp& op : request) {
    if (!out.empty()) out += "; ";
    switch (op.target) {
      case WriteOp::Target::setpoint:
        out += "setpoint " + std::to_string(op.rpm);
        break;
      case WriteOp::Target::command:
        out += to_string(op.command);
        break;
      case WriteOp::Target::point:
        out += "point " + std::to_string(op.point) + " = " + std::to_string(as_double(op.value));
        break;
      case WriteOp::Target::forward:
        out += "forward of " + std::to_string(op.pdu.size()) + " bytes";
        break;
    }
  }
  return out;
}

Published published(const Driver& d) {
  return {d.common(), d.values(), d.wake_at()};
}

void expect_same(const Published& a, const Published& b) {
  EXPECT_EQ(a.common.ready, b.common.ready);
  EXPECT_EQ(a.common.running, b.common.running);
  EXPECT_EQ(a.common.warning, b.common.warning);
  EXPECT_TRUE(a.common.faults == b.common.faults);
  EXPECT_EQ(a.common.native_fault, b.common.native_fault);
  EXPECT_EQ(a.common.speed_rpm, b.common.speed_rpm);
  EXPECT_EQ(a.common.setpoint_rpm, b.common.setpoint_rpm);
  EXPECT_EQ(a.common.command, b.common.command);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.wake_at, b.wake_at);
}

}  // namespace drivegate::test
