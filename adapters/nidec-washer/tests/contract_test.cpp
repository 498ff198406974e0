// The driver alone, where the contract of include/drivegate/driver.h is about one call: the
// verdicts of on_receive(), and check() judging a request with no side effects and exactly as
// apply() then takes its parts, for every short request in every state that matters.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "driver.h"
#include "driver_by_hand.h"
#include "points.h"
#include "write_contract.h"

namespace drivegate::nidec {
namespace {

using test::WriteContract;

using namespace std::chrono_literals;

// A driver from the adapter's own factory, with the default options, and the inverter's side
// played by hand: every frame ACKed at once with the Error byte the inverter holds.
struct Hand : test::DriverByHand {
  Hand() : DriverByHand(test::make_driver(drivegate_adapter)) {}

  // Answers the exchange the driver wants now, after waiting up to a poll interval for it; false
  // when it wants none.
  bool exchange() {
    std::optional<Exchange> ex = d->next_exchange(now);
    if (!ex) {
      now += 500ms;
      ex = d->next_exchange(now);
    }
    if (!ex) return false;
    const Decoded<Request> req = decode_request(ex->frame);
    EXPECT_EQ(req.status, DecodeStatus::frame);
    const Request& r = req.frame;
    sent.push_back(ex->frame);
    now += 50ms;
    Bytes ack;
    switch (r.mode) {
      case Mode::ping:  // 5.1: platform, version
        ack = encode_reply(r.mode, {r.data[0], 0x01, 0x07, 0});
        break;
      case Mode::forced_brake:  // 5.13: the state it is in now
        ack = encode_reply(r.mode, {error_byte, 0, 0, r.data[0]});
        break;
      case Mode::fct_test:  // 5.15
        ack = encode_fct_reply({0, error_byte});
        break;
      default:
        ack = encode_reply(r.mode, {error_byte, 0, 0, 0});
        break;
    }
    EXPECT_EQ(d->on_receive(ack, now).kind, RxKind::reply);
    return true;
  }
  bool turn() override { return exchange(); }
  void ready() {
    ASSERT_TRUE(exchange());
    ASSERT_TRUE(d->common().ready);
  }
  // Applies and settles one part as the gateway would; its outcome.
  std::optional<WriteResult> take(const WriteOp& op) {
    const WriteStatus s = apply(op);
    if (s == WriteStatus::done) return WriteResult::ok;
    if (s != WriteStatus::pending) return std::nullopt;
    return settle(ticket);
  }
  // The mode of the last frame the driver sent.
  [[nodiscard]] Mode last_mode() const { return decode_request(sent.back()).frame.mode; }

  std::uint8_t error_byte = 0;  // the Error byte (section 8) of the inverter's ACKs
};

TEST(NidecContract, VerdictsOnWhatComesBack) {
  Hand h;
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, encode(make_ping(7, 0)));
  EXPECT_EQ(ex->reply, ReplyMode::expected);
  EXPECT_EQ(ex->attempts, 3);
  EXPECT_EQ(ex->timeout, 100ms);  // section 6
  EXPECT_EQ(h.d->traits().inter_frame_gap, 5ms);
  EXPECT_EQ(h.d->traits().write_timeout, 3000ms);
  // A good ACK of another mode: a late answer to an earlier frame, foreign.
  const Bytes stale = encode_reply(Mode::request, {0, 0, 0, 0});
  EXPECT_EQ(h.d->on_receive(stale, h.now).kind, RxKind::foreign);
  EXPECT_EQ(h.d->on_receive(stale, h.now).consumed, stale.size());
  // What the codec rejects: a bad XOR costs an attempt, a byte that starts no frame is noise.
  Bytes bad = encode_reply(Mode::ping, {7, 1, 7, 0});
  bad.back() ^= 0x01;
  EXPECT_EQ(h.d->on_receive(bad, h.now).kind, RxKind::bad_checksum);
  EXPECT_EQ(h.d->on_receive(bad, h.now).consumed, bad.size());
  const Bytes noise{0x13, 0xA5};
  EXPECT_EQ(h.d->on_receive(noise, h.now).kind, RxKind::noise);
  EXPECT_EQ(h.d->on_receive(noise, h.now).consumed, 1u);
  // A mode V07 does not have (0x19, removed in V07): noise, one byte at a time.
  const Bytes clutch{0xA5, 0x19, 0x00, 0x00, 0x00, 0x01, 0xBD};
  EXPECT_EQ(h.d->on_receive(clutch, h.now).kind, RxKind::noise);
  EXPECT_EQ(h.d->on_receive(ByteView(clutch).first(6), h.now).kind, RxKind::noise);
  EXPECT_EQ(h.d->on_receive(ByteView(bad).first(6), h.now).kind, RxKind::incomplete);
  EXPECT_EQ(h.d->on_receive(encode_nack(), h.now).kind, RxKind::nack);  // 5.16
  EXPECT_FALSE(h.d->common().ready);
  const Bytes ack = encode_reply(Mode::ping, {7, 1, 7, 0});
  EXPECT_EQ(h.d->on_receive(ack, h.now).kind, RxKind::reply);
  EXPECT_TRUE(h.d->common().ready);
  // Nothing is awaited any more: even the right mode is foreign now.
  EXPECT_EQ(h.d->on_receive(ack, h.now).kind, RxKind::foreign);
}

TEST(NidecContract, AQueuedWriteIsSentOnlyInAttemptsThatStartBeforeItsDeadline) {
  Hand h;
  h.ready();
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::stop)), WriteStatus::pending);
  const TimePoint applied = h.now;
  // Unanswered turns, as the engine reports them, until the deadline is near.
  std::optional<Exchange> ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->attempts, 3);
  h.now = applied + 2400ms;
  h.d->on_no_reply(h.now);
  ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, encode(make_bare(Mode::stop)));
  // 100 ms left of 2.5 s: one attempt of 100 ms, the frame and its echo (2 x 11 characters at
  // 4800 8O1) and the gap starts before it.
  EXPECT_EQ(ex->attempts, 1);
  h.now = applied + 2500ms;
  h.d->on_no_reply(h.now);
  ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, encode(make_bare(Mode::request)));  // the stop expired: a poll
  std::vector<Completion> done;
  h.d->take_completions(done);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].result, WriteResult::no_response);
  EXPECT_EQ(h.d->common().command, Command::stop);
}

// --- check() and apply() ---

// The parts requests are made of: every command, setpoints in and out of range, and points
// that change what a later part meets (the motion, the forced brake) or that the driver refuses.
std::vector<WriteOp> parts() {
  return {
      WriteOp::of_command(Command::stop),
      WriteOp::of_command(Command::run_forward),
      WriteOp::of_command(Command::run_reverse),
      WriteOp::of_command(Command::quick_stop),
      WriteOp::of_command(Command::reset_fault),
      WriteOp::of_setpoint(800),
      WriteOp::of_setpoint(-1),
      WriteOp::of_setpoint(70000),
      WriteOp::of_point(pt::motion, std::int64_t{0}),
      WriteOp::of_point(pt::motion, std::int64_t{1}),
      WriteOp::of_point(pt::action,
                        std::int64_t{static_cast<std::int64_t>(Action::forced_brake_enable)}),
      WriteOp::of_point(pt::action,
                        std::int64_t{static_cast<std::int64_t>(Action::forced_brake_disable)}),
      WriteOp::of_point(pt::accel_time, 6553.6),
      WriteOp::of_point(pt::agitation_cw_on, 25.6),
      WriteOp::of_point(pt::weight, std::int64_t{1}),
  };
}

// Every request of one part, of two, and of three (the third from every other part).
std::vector<test::Request> requests() {
  const std::vector<WriteOp> ops = parts();
  std::vector<test::Request> out;
  for (std::size_t a = 0; a < ops.size(); ++a) {
    out.push_back({ops[a]});
    for (std::size_t b = 0; b < ops.size(); ++b) {
      out.push_back({ops[a], ops[b]});
      for (std::size_t c = 0; c < ops.size(); c += 2) out.push_back({ops[a], ops[b], ops[c]});
    }
  }
  return out;
}

enum class State { idle, faulted, forced_brake, spinning };

// A ready driver in `state`.
void enter(Hand& h, State state) {
  h.ready();
  switch (state) {
    case State::idle:
      return;
    case State::faulted:  // a stall the inverter keeps reporting (section 8)
      h.error_byte = 0x08;
      ASSERT_TRUE(h.exchange());
      ASSERT_EQ(h.d->common().native_fault, 0x08u);
      return;
    case State::forced_brake:  // 5.13
      ASSERT_EQ(
          h.take(WriteOp::of_point(
              pt::action, std::int64_t{static_cast<std::int64_t>(Action::forced_brake_enable)})),
          WriteResult::ok);
      return;
    case State::spinning:  // 5.6: forward only
      ASSERT_EQ(h.take(WriteOp::of_point(pt::motion, std::int64_t{1})), WriteResult::ok);
      ASSERT_EQ(h.take(WriteOp::of_setpoint(1200)), WriteResult::ok);
      ASSERT_EQ(h.take(WriteOp::of_command(Command::run_forward)), WriteResult::ok);
      ASSERT_EQ(h.d->common().command, Command::run_forward);
      return;
  }
}

std::vector<test::WriteState> states() {
  return test::write_states<Hand>(enter, {"idle", "faulted", "forced brake", "spinning"});
}

// A part whose ACK carries Error bits ends the request there, as it ends it at the gateway: the
// drive's verdict, not check()'s.
INSTANTIATE_TEST_SUITE_P(Nidec, WriteContract,
                         testing::Values(test::WriteContractCase{.name = "nidec-washer",
                                                                 .states = states,
                                                                 .requests = requests,
                                                                 .turns = 10,
                                                                 .device_refuses_anywhere = true,
                                                                 .min_judged = 1001}));

TEST(NidecContract, ARequestIsJudgedAgainstWhatItsEarlierPartsLeave) {
  Hand h;
  enter(h, State::spinning);
  const WriteOp reverse = WriteOp::of_command(Command::run_reverse);
  const WriteOp rotation = WriteOp::of_point(pt::motion, std::int64_t{0});
  // 5.6: spin has no direction, but CW / CCW do (5.3 / 5.4).
  EXPECT_EQ(h.d->check(std::vector{reverse}), WriteCheck::invalid_value);
  EXPECT_EQ(h.d->check(std::vector{rotation, reverse}), WriteCheck::ok);
  EXPECT_EQ(h.d->check(std::vector{reverse, rotation}), WriteCheck::invalid_value);
  // A forced brake enabled earlier in the request refuses the run after it (5.13).
  const WriteOp brake = WriteOp::of_point(
      pt::action, std::int64_t{static_cast<std::int64_t>(Action::forced_brake_enable)});
  const WriteOp forward = WriteOp::of_command(Command::run_forward);
  EXPECT_EQ(h.d->check(std::vector{brake, forward}), WriteCheck::refused);
  // Nothing of it was applied: the motion for the next run is still spin.
  EXPECT_EQ(std::get<std::int64_t>(h.d->values()[pt::motion]), 1);
  EXPECT_EQ(h.last_mode(), Mode::spin);
  EXPECT_EQ(h.d->next_exchange(h.now), std::nullopt);  // no frame queued by check()
}

TEST(NidecContract, AResetFaultEarlierInTheRequestLetsTheRunAfterIt_section8) {
  Hand h;
  enter(h, State::faulted);
  const WriteOp reset = WriteOp::of_command(Command::reset_fault);
  const WriteOp forward = WriteOp::of_command(Command::run_forward);
  EXPECT_EQ(h.d->check(std::vector{forward}), WriteCheck::refused);
  // The reset succeeds only when its ACK shows no fault, and then the run meets none.
  EXPECT_EQ(h.d->check(std::vector{reset, forward}), WriteCheck::ok);
  EXPECT_EQ(h.d->check(std::vector{forward, reset}), WriteCheck::refused);
  // The stall cleared by itself (section 8: after 4 s); the driver has not heard yet.
  h.error_byte = 0;
  EXPECT_EQ(h.take(reset), WriteResult::ok);
  EXPECT_EQ(h.take(forward), WriteResult::ok);
  EXPECT_EQ(h.d->common().command, Command::run_forward);
}

}  // namespace
}  // namespace drivegate::nidec
