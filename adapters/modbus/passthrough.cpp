#include "passthrough.h"

#include "line_timing.h"
#include "presence_probe.h"
#include "rejected.h"

namespace drivegate::modbus_device {
PassthroughDriver::PassthroughDriver(std::uint8_t address, PassthroughSettings settings,
                                     std::chrono::nanoseconds char_time, Millis poll_interval)
    : address_(address),
      settings_(settings),
      char_time_(char_time),
      poll_interval_(poll_interval) {}

// A forwarded request's reply may be of any length: its exchange is counted with the longest.
Millis PassthroughDriver::send_limit() const {
  const Millis probe = exchange_time(settings_.framing, char_time_, settings_.reply_timeout,
                                     settings_.attempts, longest_frame(settings_.framing));
  return probe + kOtherTurnAllowance;
}

DriverTraits PassthroughDriver::traits() const {
  DriverTraits t;
  t.comm_timeout = settings_.comm_timeout;
  t.inter_frame_gap = inter_frame_gap(settings_.framing, char_time_);
  // One part: on the line within send_limit(), then one exchange of its own.
  t.write_timeout = write_backstop(send_limit(), 1);
  return t;
}

std::optional<Exchange> PassthroughDriver::next_exchange(TimePoint now) {
  last_now_ = now;
  // Not on the line by its send-by: failed, and never sent (as ModbusDriver's writes).
  queued_.expire_after(now);
  // The engine asks only once the exchange before ended: one it abandoned without a word still
  // owes its client an answer.
  abandon();
  Exchange ex;
  ex.reply = ReplyMode::expected;
  if (!queued_.empty()) {
    Forwards::Entry f = queued_.take_front();
    ex.frame = encode(settings_.framing, address_, f.job.pdu);
    // Any reply, up to the longest frame, must have time to arrive.
    ex.timeout =
        reply_timeout(settings_.reply_timeout, char_time_, longest_frame(settings_.framing));
    ex.attempts = 1;
    inflight_ = InFlight{f.job.pdu[0], std::move(f)};
    return ex;
  }
  if (now < probe_due_) return std::nullopt;
  probe_due_ = now + poll_interval_;
  ex.frame = encode(settings_.framing, address_, kPresenceProbe);
  // The probe's reply is at most 7 bytes (exception: 5), 15 characters in ASCII.
  ex.timeout = reply_timeout(settings_.reply_timeout, char_time_, 15);
  ex.attempts = settings_.attempts;
  inflight_ = InFlight{kPresenceProbe[0], std::nullopt};
  return ex;
}

TimePoint PassthroughDriver::wake_at() const {
  return queued_.empty() ? probe_due_ : last_now_;
}

RxVerdict PassthroughDriver::on_receive(ByteView rx, TimePoint now) {
  last_now_ = now;
  if (rx.empty()) return {};
  if (!inflight_) return {RxKind::noise, rx.size()};
  const Decoded<Adu> d = decode_reply(settings_.framing, rx);
  switch (d.status) {
    case DecodeStatus::incomplete:
      return {};
    case DecodeStatus::bad:
      return rejected(settings_.framing, d, rx, address_);
    case DecodeStatus::frame:
      break;
  }
  const Adu& a = d.frame;
  const std::uint8_t fn = inflight_->function;
  // The reply to this request: the same function, or its exception (Application Protocol 7).
  if (a.address != address_ || (a.pdu[0] != fn && a.pdu[0] != (fn | kExceptionBit))) {
    return {RxKind::foreign, d.consumed};
  }
  InFlight done = std::move(*inflight_);
  inflight_.reset();
  common_.ready = true;
  if (done.forward) queued_.settle(*done.forward, WriteResult::ok, a.pdu);
  // Neither a forwarded reply nor the probe's is state the gateway keeps.
  return {RxKind::ack, d.consumed};
}

void PassthroughDriver::on_no_reply(TimePoint now) {
  last_now_ = now;
  abandon();
}

void PassthroughDriver::on_comm_lost(TimePoint now) {
  last_now_ = now;
  abandon();
  queued_.settle_all(WriteResult::no_response);
  common_.ready = false;
  probe_due_ = now;
}

WriteCheck PassthroughDriver::check(std::span<const WriteOp> request) const {
  for (const WriteOp& op : request) {
    if (op.target != WriteOp::Target::forward) return WriteCheck::invalid_value;
    if (op.pdu.empty() || op.pdu.size() > kMaxPdu) return WriteCheck::invalid_value;
  }
  return WriteCheck::ok;
}

WriteStatus PassthroughDriver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  last_now_ = now;
  const WriteOp one[] = {op};
  if (check(one) != WriteCheck::ok) return WriteStatus::invalid_value;
  queued_.push({op.pdu}, t, now + send_limit());
  return WriteStatus::pending;
}

void PassthroughDriver::abandon() {
  if (inflight_ && inflight_->forward) {
    queued_.settle(*inflight_->forward, WriteResult::no_response);
  }
  inflight_.reset();
}

}  // namespace drivegate::modbus_device
