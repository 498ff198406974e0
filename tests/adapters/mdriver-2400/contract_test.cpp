// The driver alone, where the contract of include/drivegate/driver.h is about one call: the
// verdicts of on_receive(), check() judging a request with no side effects and exactly as apply()
// then takes its parts, and the failures of writes nothing on the bus would show at once.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "codec.h"
#include "driver.h"

namespace drivegate::mdriver {
namespace {

using namespace std::chrono_literals;

// A driver from the adapter's own factory, with the default options, and the drive's side played
// by hand: every run command echoed with the error code the drive holds.
struct Hand {
  Hand() {
    DeviceEnv env;
    env.address = 1;
    env.options = test::options_of(drivegate_adapter);
    std::string error;
    d = drivegate_adapter.create_driver(env, error);
    EXPECT_NE(d, nullptr) << error;
  }

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
  // The check, then the first status.
  void ready() {
    exchange();
    exchange();
    ASSERT_TRUE(d->common().ready);
  }
  WriteStatus apply(const WriteOp& op) { return d->apply(op, ++ticket, now); }
  std::vector<Completion> completions() {
    std::vector<Completion> out;
    d->take_completions(out);
    return out;
  }

  std::unique_ptr<Driver> d;
  TimePoint now = TimePoint{} + 1h;
  std::uint8_t r7 = 0;  // the error code of the drive's replies
  Ticket ticket = 0;
  std::vector<Bytes> sent;
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

std::vector<std::vector<WriteOp>> requests() {
  std::vector<std::vector<WriteOp>> out;
  const std::optional<std::int32_t> setpoints[] = {std::nullopt, 503, 600, 1149, 2857};
  for (const auto& rpm : setpoints) {
    std::vector<WriteOp> base;
    if (rpm) base.push_back(WriteOp::of_setpoint(*rpm));
    if (!base.empty()) out.push_back(base);
    for (const Command c : kAllCommands) {
      auto r = base;
      r.push_back(WriteOp::of_command(c));
      out.push_back(r);
    }
  }
  out.push_back({WriteOp::of_point(0, Value{std::int64_t{1}})});
  return out;
}

WriteCheck as_check(WriteStatus s) {
  return s == WriteStatus::invalid_value ? WriteCheck::invalid_value : WriteCheck::refused;
}

TEST(MdriverContract, CheckAcceptsARequestExactlyWhenApplyTakesItsPartsInOrder) {
  for (const State s :
       {State::not_ready, State::stopped, State::stored, State::running, State::tripped}) {
    for (const auto& request : requests()) {
      SCOPED_TRACE(testing::Message()
                   << "state " << static_cast<int>(s) << ", request of " << request.size()
                   << " parts, last " << static_cast<int>(request.back().target) << "/"
                   << static_cast<int>(request.back().command) << "/" << request.back().rpm);
      Hand h;
      bring(h, s);
      const WriteCheck judged = h.d->check(request);
      // Applied as the gateway applies it: a part once the one before it settled.
      WriteCheck applied = WriteCheck::ok;
      for (const WriteOp& op : request) {
        const WriteStatus st = h.apply(op);
        if (st == WriteStatus::invalid_value || st == WriteStatus::refused) {
          applied = as_check(st);
          break;
        }
        if (st == WriteStatus::pending) {
          ASSERT_TRUE(h.exchange());
          const auto c = h.completions();
          ASSERT_EQ(c.size(), 1u);
          ASSERT_EQ(c[0].ticket, h.ticket);
          ASSERT_EQ(c[0].result, WriteResult::ok);
        }
      }
      EXPECT_EQ(judged, applied);
    }
  }
}

TEST(MdriverContract, CheckHasNoSideEffects) {
  for (const State s :
       {State::not_ready, State::stopped, State::stored, State::running, State::tripped}) {
    SCOPED_TRACE(static_cast<int>(s));
    Hand judged;
    Hand untouched;
    bring(judged, s);
    bring(untouched, s);
    for (const auto& request : requests()) (void)judged.d->check(request);
    EXPECT_TRUE(judged.completions().empty());
    const CommonState& a = judged.d->common();
    const CommonState& b = untouched.d->common();
    EXPECT_EQ(a.command, b.command);
    EXPECT_EQ(a.setpoint_rpm, b.setpoint_rpm);
    EXPECT_EQ(a.running, b.running);
    EXPECT_EQ(a.ready, b.ready);
    EXPECT_EQ(judged.d->values(), untouched.d->values());
    EXPECT_EQ(judged.d->wake_at(), untouched.d->wake_at());
    // And the line carries the same from here on.
    for (int i = 0; i < 3; ++i) {
      judged.now += 2s;
      untouched.now += 2s;
      judged.exchange();
      untouched.exchange();
    }
    EXPECT_EQ(judged.sent, untouched.sent);
  }
}

TEST(MdriverContract, AWriteNotConfirmedInTimeFailsAtTheDriversOwnDeadline) {
  Hand h;
  h.ready();
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::stop)), WriteStatus::pending);
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, encode_run(0x00, 0x01, kStopCode, kChangeNormal));
  // No reply, and no on_no_reply either: the driver's own deadline, under the gateway's 3 s.
  EXPECT_LE(h.d->wake_at(), h.now + kConfirmDeadline);
  EXPECT_TRUE(h.completions().empty());
  (void)h.d->next_exchange(h.now + kConfirmDeadline);
  const auto c = h.completions();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].ticket, h.ticket);
  EXPECT_EQ(c[0].result, WriteResult::no_response);
  EXPECT_LT(kConfirmDeadline, h.d->traits().write_timeout);
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
