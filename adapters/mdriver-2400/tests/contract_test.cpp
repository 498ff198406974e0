// The driver alone, where the contract of include/drivegate/driver.h is about one call: the
// verdicts of on_receive(), check() judging a request with no side effects and exactly as apply()
// then takes its parts, and the failures of writes nothing on the bus would show at once.
#include <gtest/gtest.h>

#include <memory>
#include <utility>
#include <vector>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "driver.h"
#include "driver_by_hand.h"
#include "write_contract.h"

namespace drivegate::mdriver {
namespace {

using test::WriteContract;

using namespace std::chrono_literals;

// A driver from the adapter's own factory, with the default options, and the drive's side played
// by hand: every run command echoed with the error code the drive holds.
struct Hand : test::DriverByHand {
  Hand() : DriverByHand(test::make_driver(drivegate_adapter, {.address = 1})) {}

  // Answers the exchange the driver wants now; false when it wants none.
  bool exchange() {
    const auto ex = d->next_exchange(now);
    if (!ex) return false;
    sent.push_back(ex->frame);
    now += 100ms;
    const Bytes reply =
        ex->frame[2] == static_cast<std::uint8_t>(Cmd::check)
            ? encode_check_reply(0x01, 0x00, kFixedCode)
            : encode_run_reply(0x01, 0x00, RunReply{ex->frame[4], 0, 0, r7, 0x1A, {}});
    EXPECT_EQ(d->on_receive(reply, now).kind, RxKind::reply);
    return true;
  }
  bool turn() override {
    if (!exchange()) now += 100ms;
    return true;
  }
  // The check, then the first status.
  void ready() {
    exchange();
    exchange();
    ASSERT_TRUE(d->common().ready);
  }

  std::uint8_t r7 = 0;  // the error code of the drive's replies
};

TEST(MdriverContract, VerdictsOnWhatComesBack) {
  Hand h;
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, encode_check(0x00, 0x01));
  EXPECT_EQ(ex->reply, ReplyMode::expected);
  EXPECT_EQ(ex->attempts, kAttempts);
  EXPECT_EQ(ex->timeout, kReplyTimeout);
  EXPECT_FALSE(h.d->next_exchange(h.now).has_value());  // one at a time
  EXPECT_EQ(h.d->traits().comm_timeout, 6000ms);        // the driver's own trip (error 0x0C)
  EXPECT_EQ(h.d->traits().inter_frame_gap, kInterFrameGap);
  // Another driver's echo, and the master's own frame heard back: foreign.
  const Bytes other = encode_check_reply(0x02, 0x00, kFixedCode);
  EXPECT_EQ(h.d->on_receive(other, h.now).kind, RxKind::foreign);
  EXPECT_EQ(h.d->on_receive(other, h.now).consumed, other.size());
  EXPECT_EQ(h.d->on_receive(encode_check(0x00, 0x01), h.now).kind, RxKind::foreign);
  // A run reply while the check is awaited: a late frame, foreign.
  EXPECT_EQ(h.d->on_receive(encode_run_reply(0x01, 0x00, RunReply{}), h.now).kind, RxKind::foreign);
  // What the codec rejects: a bad checksum costs an attempt, a bad command byte is noise.
  Bytes bad = encode_check_reply(0x01, 0x00, kFixedCode);
  bad.back() ^= 1;
  EXPECT_EQ(h.d->on_receive(bad, h.now).kind, RxKind::bad_checksum);
  EXPECT_EQ(h.d->on_receive(bad, h.now).consumed, bad.size());
  const Bytes noise{0xFF, 0xFF, 0x33};
  EXPECT_EQ(h.d->on_receive(noise, h.now).kind, RxKind::noise);
  EXPECT_EQ(h.d->on_receive(noise, h.now).consumed, 1u);
  // Half a frame waits for the rest.
  const Bytes good = encode_check_reply(0x01, 0x00, kFixedCode);
  EXPECT_EQ(h.d->on_receive(ByteView(good).first(4), h.now).kind, RxKind::incomplete);
  EXPECT_EQ(h.d->on_receive(good, h.now).kind, RxKind::reply);
  EXPECT_TRUE(h.d->common().ready);
  EXPECT_EQ(h.d->points().size(), h.d->values().size());
}

// The states a request may find the driver in.
enum class State { not_ready, stopped, stored, running, tripped };

void bring(Hand& h, State s) {
  if (s == State::not_ready) return;
  h.ready();
  if (s == State::stopped) return;
  ASSERT_EQ(h.apply(WriteOp::of_setpoint(1149)), WriteStatus::done);
  if (s == State::stored) return;
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::run_forward)), WriteStatus::pending);
  ASSERT_TRUE(h.exchange());
  ASSERT_EQ(h.d->common().command, Command::run_forward);
  ASSERT_EQ(h.completions().size(), 1u);
  if (s == State::running) return;
  h.r7 = 0x04;  // stall: the next status shows it latched
  h.now += 1s;
  ASSERT_TRUE(h.exchange());
  ASSERT_FALSE(h.d->common().faults.empty());
}

std::vector<test::WriteState> states() {
  return test::write_states<Hand>(
      bring, {"not ready", "stopped", "setpoint stored", "running", "tripped"});
}

std::vector<test::Request> requests() {
  auto out = test::command_requests({503, 600, 1149, 2857});
  out.push_back({WriteOp::of_point(0, Value{std::int64_t{1}})});
  return out;
}

// Every part the drive is sent, it takes: a refusal is check()'s to give.
INSTANTIATE_TEST_SUITE_P(
    Mdriver, WriteContract,
    testing::Values(test::WriteContractCase{
        .name = "mdriver-2400", .states = states, .requests = requests, .turns = 60}));

TEST(MdriverContract, AWriteNotConfirmedInTimeFailsAtTheDriversOwnDeadline) {
  Hand h;
  h.ready();
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::stop)), WriteStatus::pending);
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, encode_run(0x00, 0x01, kStopCode, kChangeNormal));
  // No reply, and no on_no_reply either: the driver's own deadline, under the gateway's 3 s.
  test::expect_fails_at_own_deadline(h, h.now, kConfirmDeadline);
}

TEST(MdriverContract, CommLostFailsTheWritesInFlightAndKeepsWhatIsInForce) {
  Hand h;
  bring(h, State::running);
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::stop)), WriteStatus::pending);
  h.d->on_comm_lost(h.now);
  const auto c = h.completions();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].ticket, h.ticket);
  EXPECT_EQ(c[0].result, WriteResult::no_response);
  EXPECT_FALSE(h.d->common().ready);
  EXPECT_EQ(h.d->common().command, Command::run_forward);  // the stop never reached the drive
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, encode_check(0x00, 0x01));
}

}  // namespace
}  // namespace drivegate::mdriver
