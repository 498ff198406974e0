// The driver alone, where the contract of include/drivegate/driver.h is about one call: the
// verdicts of on_receive(), the exchanges it asks for, check() judging a request with no side
// effects and exactly as apply() then takes its parts, and the failures of writes that nothing on
// the line shows at once.
#include <gtest/gtest.h>

#include <memory>
#include <utility>
#include <vector>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "driver.h"
#include "driver_by_hand.h"
#include "op_state.h"
#include "payloads.h"
#include "write_contract.h"

namespace drivegate::unicla {
namespace {

using test::WriteContract;

using namespace std::chrono_literals;

// A driver from the adapter's own factory with the default options, and the drive's side played
// by hand: every read answered from what the drive holds, every write taken (Set Run State runs
// the motor at its speed or stops it, Acknowledge Faults clears a fault).
struct Hand : test::DriverByHand {
  Hand() : DriverByHand(test::make_driver(drivegate_adapter, {.address = 1, .poll = 500ms})) {
    limits.min_speed = 1500;
    limits.max_speed = 6000;
    limits.device_id = 1;
    limits.control_enabled = 1;
    status.op_state = static_cast<std::uint8_t>(OpState::stopped);
  }

  // The exchange the driver wants now, carried out; false when it wants none.
  bool exchange() {
    const auto ex = d->next_exchange(now);
    if (!ex) return false;
    sent.push_back(ex->frame);
    const Frame f = decode(ex->frame).frame;
    now += 20ms;
    if (f.command == static_cast<std::uint8_t>(CommandByte::write)) {
      EXPECT_EQ(ex->reply, ReplyMode::none);
      take(f);
      return true;
    }
    Frame r;
    r.source = 0x01;
    r.command = f.command;
    r.message_id = f.message_id;
    r.sequence = f.sequence;
    switch (static_cast<MessageId>(f.message_id)) {
      case MessageId::build_information:
        r.payload = encode_build_info(build, ByteOrder::big);
        break;
      case MessageId::running_limits:
        r.payload = encode_running_limits(limits, ByteOrder::big);
        break;
      default:
        r.payload = encode_status(status, ByteOrder::big);
        break;
    }
    EXPECT_EQ(d->on_receive(encode(r), now).kind, RxKind::reply);
    return true;
  }
  void take(const Frame& f) {
    if (f.message_id == static_cast<std::uint8_t>(MessageId::acknowledge_faults)) {
      if (is_fault_state(status.op_state))
        status.op_state = static_cast<std::uint8_t>(OpState::stopped);
      return;
    }
    const std::uint16_t rpm = *parse_speed(f.payload);
    status.rpm = rpm;
    status.op_state = static_cast<std::uint8_t>(rpm == 0 ? OpState::stopped : OpState::running);
  }
  bool turn() override {
    if (!exchange()) now += 10ms;
    return true;
  }
  // Build information, running limits, the first status.
  void ready() {
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(exchange());
    ASSERT_TRUE(d->common().ready);
  }

  BuildInfo build;
  RunningLimits limits;
  Status status;
};

TEST(UniclaContract, ExchangesAsTheDocumentAsks) {
  Hand h;
  const auto read = h.d->next_exchange(h.now);
  ASSERT_TRUE(read.has_value());
  EXPECT_EQ(read->reply, ReplyMode::expected);  // "Successful read commands always get a reply"
  EXPECT_EQ(read->attempts, 3);                 // 1 + retries
  EXPECT_EQ(read->timeout, 100ms);
  EXPECT_EQ(h.d->traits().inter_frame_gap, kInterFrameGap);
  EXPECT_EQ(h.d->points().size(), h.d->values().size());

  Hand w;
  w.ready();
  ASSERT_EQ(w.apply(WriteOp::of_command(Command::stop)), WriteStatus::pending);
  EXPECT_EQ(w.d->wake_at(), TimePoint{});  // due at once
  const auto write = w.d->next_exchange(w.now);
  ASSERT_TRUE(write.has_value());
  EXPECT_EQ(write->reply, ReplyMode::none);  // "Write commands are not acknowledged"
  EXPECT_EQ(write->attempts, 1);
  // The confirming status read right after it.
  const auto confirm = w.d->next_exchange(w.now);
  ASSERT_TRUE(confirm.has_value());
  EXPECT_EQ(decode(confirm->frame).frame.message_id, static_cast<std::uint8_t>(MessageId::status));
}

TEST(UniclaContract, VerdictsOnWhatComesBack) {
  Hand h;
  h.ready();
  h.now += 1s;
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  const Frame req = decode(ex->frame).frame;
  Frame rep;
  rep.source = 0x01;
  rep.command = 0xC0;
  rep.message_id = static_cast<std::uint8_t>(MessageId::status);
  rep.sequence = static_cast<std::uint8_t>(req.sequence - 1);  // a late reply to an earlier read
  rep.payload = encode_status(h.status, ByteOrder::big);
  Bytes wire = encode(rep);
  RxVerdict v = h.d->on_receive(wire, h.now);
  EXPECT_EQ(v.kind, RxKind::foreign);
  EXPECT_EQ(v.consumed, wire.size());
  rep.sequence = req.sequence;
  rep.source = 0x02;  // another drive
  EXPECT_EQ(h.d->on_receive(encode(rep), h.now).kind, RxKind::foreign);
  rep.source = 0x01;
  rep.destination = 0x05;  // not for the master
  EXPECT_EQ(h.d->on_receive(encode(rep), h.now).kind, RxKind::foreign);
  EXPECT_EQ(h.d->on_receive(ex->frame, h.now).kind, RxKind::foreign);  // the request itself
  rep.destination = 0x00;
  rep.message_id = static_cast<std::uint8_t>(MessageId::build_information);  // wrong message
  EXPECT_EQ(h.d->on_receive(encode(rep), h.now).kind, RxKind::foreign);
  rep.message_id = static_cast<std::uint8_t>(MessageId::status);
  rep.payload.resize(10);  // checked, but too short for a status
  wire = encode(rep);
  v = h.d->on_receive(wire, h.now);
  EXPECT_EQ(v.kind, RxKind::noise);
  EXPECT_EQ(v.consumed, wire.size());
  rep.payload = encode_status(h.status, ByteOrder::big);
  wire = encode(rep);
  // Split at every byte: incomplete until the EOF, then the reply.
  for (std::size_t n = 1; n < wire.size(); ++n) {
    const RxVerdict part = h.d->on_receive(ByteView(wire).first(n), h.now);
    ASSERT_EQ(part.kind, RxKind::incomplete) << n;
    EXPECT_EQ(part.consumed, 0u);
  }
  v = h.d->on_receive(wire, h.now);
  EXPECT_EQ(v.kind, RxKind::reply);
  EXPECT_EQ(v.consumed, wire.size());
  // Answered once: the same reply again is foreign.
  EXPECT_EQ(h.d->on_receive(wire, h.now).kind, RxKind::foreign);
}

TEST(UniclaContract, WhatTheCodecRejectsIsDamagedOrNoise) {
  Hand h;
  // Bytes before a flag: noise, up to the flag that may open a frame.
  const Bytes noise = {0x01, 0x02, 0x7E};
  RxVerdict v = h.d->on_receive(noise, h.now);
  EXPECT_EQ(v.kind, RxKind::noise);
  EXPECT_EQ(v.consumed, 2u);
  // A frame whose CRC does not hold costs the exchange an attempt; its closing flag is kept.
  const Bytes bad_crc = {0x7E, 0x01, 0x00, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0x00, 0x00, 0x7E};
  v = h.d->on_receive(bad_crc, h.now);
  EXPECT_EQ(v.kind, RxKind::bad_checksum);
  EXPECT_EQ(v.consumed, 11u);
  // A bad escape or length: noise.
  const Bytes bad_escape = {0x7E, 0x01, 0x7D, 0x01, 0x7E};
  EXPECT_EQ(h.d->on_receive(bad_escape, h.now).kind, RxKind::noise);
}

// The states a request may find the driver in.
enum class State { not_ready, stopped, stored, running, tripped, control_off };

void bring(Hand& h, State s) {
  if (s == State::not_ready) return;
  if (s == State::control_off) h.limits.control_enabled = 0;
  h.ready();
  if (s == State::stopped || s == State::control_off) return;
  ASSERT_EQ(h.apply(WriteOp::of_setpoint(3000)), WriteStatus::done);
  if (s == State::stored) return;
  ASSERT_TRUE(test::runs_forward(h));
  h.completions();  // the set-up's own
  if (s == State::running) return;
  h.status.op_state = static_cast<std::uint8_t>(OpState::fault_motor);
  h.now += 1s;
  ASSERT_TRUE(h.exchange());
  ASSERT_FALSE(h.d->common().faults.empty());
}

std::vector<test::WriteState> states() {
  return test::write_states<Hand>(
      bring, {"not ready", "stopped", "setpoint stored", "running", "tripped", "control off"});
}

std::vector<test::Request> requests() {
  auto out = test::command_requests({-5, 0, 1000, 1500, 3000, 6000, 7000});
  out.push_back({WriteOp::of_point(0, Value{std::int64_t{1}})});
  return out;
}

// The hand-played drive takes every write it is sent: a refusal is check()'s to give.
INSTANTIATE_TEST_SUITE_P(
    Unicla, WriteContract,
    testing::Values(test::WriteContractCase{
        .name = "unicla-edrive", .states = states, .requests = requests, .turns = 250}));

TEST(UniclaContract, AWriteNotShownInTimeFailsAtTheDriversOwnDeadline) {
  Hand h;
  h.ready();
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::reset_fault)), WriteStatus::pending);
  const TimePoint applied = h.now;
  ASSERT_TRUE(h.d->next_exchange(h.now).has_value());  // on the line, never answered
  // No status came back at all: confirm_timeout_ms (2000, the default) from the write.
  test::expect_fails_at_own_deadline(h, applied, 2000ms);
}

TEST(UniclaContract, CommLostFailsTheWritesInFlightAndKeepsWhatIsInForce) {
  Hand h;
  bring(h, State::running);
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::stop)), WriteStatus::pending);
  ASSERT_TRUE(h.d->next_exchange(h.now).has_value());                    // the stop went out
  ASSERT_EQ(h.apply(WriteOp::of_setpoint(4000)), WriteStatus::pending);  // waits behind it
  h.d->on_comm_lost(h.now);
  const auto c = h.completions();
  ASSERT_EQ(c.size(), 2u);
  for (const Completion& x : c) EXPECT_EQ(x.result, WriteResult::no_response);
  EXPECT_FALSE(h.d->common().ready);
  // Neither was shown: what was in force stays.
  EXPECT_EQ(h.d->common().command, Command::run_forward);
  EXPECT_EQ(h.d->common().setpoint_rpm, 3000);
  // The limits are forgotten until read again: a speed cannot be judged.
  EXPECT_EQ(h.d->check(std::vector{WriteOp::of_setpoint(3000)}), WriteCheck::refused);
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(decode(ex->frame).frame.message_id,
            static_cast<std::uint8_t>(MessageId::build_information));
}

TEST(UniclaContract, AWriteNotYetSentFailsOnCommLostToo) {
  Hand h;
  h.ready();
  ASSERT_EQ(h.apply(WriteOp::of_setpoint(3000)), WriteStatus::done);
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::run_forward)), WriteStatus::pending);
  h.d->on_comm_lost(h.now);  // before it even went out
  const auto c = h.completions();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].ticket, h.ticket);
  EXPECT_EQ(c[0].result, WriteResult::no_response);
  EXPECT_EQ(h.d->common().command, Command::stop);
}

}  // namespace
}  // namespace drivegate::unicla
