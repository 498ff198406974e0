#include "driver.h"

#include <algorithm>

#include "faults.h"
#include "points.h"
#include "rpm_table.h"

namespace drivegate::mdriver {

Mdriver2400Driver::Mdriver2400Driver(std::uint8_t address, const Settings& settings,
                                     Millis poll_interval)
    : settings_(settings),
      address_(address),
      // The run command is both poll and keep-alive: every min(poll, keep-alive).
      cadence_(poll_interval.count() > 0 ? std::min(poll_interval, settings.keepalive)
                                         : settings.keepalive) {
  points_ = make_points();
  values_.resize(points_.size());
  refresh();
}

DriverTraits Mdriver2400Driver::traits() const {
  DriverTraits t;
  // The gateway gives up on the drive when the drive itself gives up on the gateway.
  t.comm_timeout = kSilenceTrip;
  t.write_timeout = Millis(3000);
  t.inter_frame_gap = kInterFrameGap;
  return t;
}

bool Mdriver2400Driver::device_error() const {
  return last_ && last_->error_code != 0;
}

// The D4 of a keep-alive: what is in force, never what is merely asked for.
std::uint8_t Mdriver2400Driver::code_in_force() const {
  if (command_ == Command::run_forward && setpoint_code_) return *setpoint_code_;
  return kStopCode;
}

Exchange Mdriver2400Driver::make_exchange(Bytes frame) const {
  Exchange ex;
  ex.frame = std::move(frame);
  ex.reply = ReplyMode::expected;
  ex.timeout = kReplyTimeout;
  ex.attempts = kAttempts;
  return ex;
}

Exchange Mdriver2400Driver::run_exchange(std::uint8_t code, TimePoint now) {
  sent_code_ = code;
  next_due_ = now + cadence_;  // every run command is a keep-alive
  awaiting_ = Awaiting::run;
  refresh();
  return make_exchange(encode_run(settings_.master, address_, code, settings_.change));
}

std::optional<Exchange> Mdriver2400Driver::next_exchange(TimePoint now) {
  writes_.expire(now);
  if (awaiting_ != Awaiting::nothing) return std::nullopt;
  if (phase_ != Phase::ready) {
    // Section 3 No.1: sent after power-up and resent until the driver answers.
    if (now < next_due_) return std::nullopt;
    next_due_ = now + cadence_;
    awaiting_ = Awaiting::check;
    return make_exchange(encode_check(settings_.master, address_));
  }
  if (auto write = next_write(now)) return write;
  if (now < next_due_) return std::nullopt;
  return run_exchange(code_in_force(), now);
}

TimePoint Mdriver2400Driver::wake_at() const {
  if (phase_ == Phase::ready && !writes_.empty() && !writes_.front().sent) return TimePoint{};
  TimePoint t = next_due_;
  if (const auto deadline = writes_.next_deadline()) t = std::min(t, *deadline);
  return t;
}

RxVerdict Mdriver2400Driver::on_receive(ByteView rx, TimePoint now) {
  writes_.expire(now);
  const Decoded<Frame> d = decode(rx);
  if (const auto v = unless_frame(d)) return *v;
  const Frame& f = d.frame;
  // Section 2: the driver answers with its own address as source, the master's as destination.
  if (f.src != address_ || f.dst != settings_.master) return {RxKind::foreign, d.consumed};
  // A good frame that is not the reply awaited (a late one) is someone else's business too.
  RxKind kind = RxKind::foreign;
  if (awaiting_ == Awaiting::check && f.cmd == static_cast<std::uint8_t>(Cmd::check)) {
    kind = on_check_reply(f, now);
  } else if (awaiting_ == Awaiting::run && f.cmd == static_cast<std::uint8_t>(Cmd::run)) {
    kind = on_run_reply(f);
  }
  refresh();
  return {kind, d.consumed};
}

RxKind Mdriver2400Driver::on_check_reply(const Frame& f, TimePoint now) {
  // Section 3 No.1: four code bytes; any other layout is not a reply.
  const auto code = parse_check(f);
  if (!code) return RxKind::noise;
  awaiting_ = Awaiting::nothing;
  if (*code == kFixedCode) {
    phase_ = Phase::ready;
    next_due_ = now;  // the first run command (status) at once
  } else {
    // Section 3 No.1: 00 00 00 00 = EEPROM check failed or code mismatch. Any other answer is
    // not the echo either: the same fault. Keep checking at the poll cadence.
    phase_ = Phase::fixed_code_error;
  }
  return RxKind::reply;
}

RxKind Mdriver2400Driver::on_run_reply(const Frame& f) {
  // Section 3 No.2: eight data bytes R4..R11; any other layout is not a reply.
  const auto r = parse_run_reply(f);
  if (!r) return RxKind::noise;
  awaiting_ = Awaiting::nothing;
  last_ = *r;
  confirm(*r);
  return RxKind::reply;
}

void Mdriver2400Driver::on_no_reply(TimePoint /*now*/) {
  awaiting_ = Awaiting::nothing;
  fail_sent(WriteResult::no_response);
  refresh();
}

void Mdriver2400Driver::on_comm_lost(TimePoint now) {
  // Forget the handshake: the driver may have been powered off; check the fixed code again. What
  // is in force stays: once it answers again, the keep-alive carries it again.
  phase_ = Phase::check;
  awaiting_ = Awaiting::nothing;
  next_due_ = now;
  writes_.settle_all(WriteResult::no_response);
  refresh();
}

void Mdriver2400Driver::refresh() {
  common_.ready = phase_ == Phase::ready;
  common_.warning = false;
  common_.faults = FaultSet{};
  common_.native_fault = 0;
  if (phase_ == Phase::fixed_code_error) {
    common_.faults.set(Fault::hardware_fault);
    common_.native_fault = kNativeFixedCodeError;
  } else if (device_error()) {
    common_.faults.set(fault_of(last_->error_code));
    common_.native_fault = last_->error_code;
  }
  const bool turning = last_ && last_->actual_code > kCodeStopMax;
  common_.speed_rpm = last_ ? rpm_of_code(last_->actual_code) : 0;
  common_.running = turning || (command_ == Command::run_forward && !device_error());
  common_.setpoint_rpm = setpoint_code_ ? rpm_of_code(*setpoint_code_) : 0;
  common_.command = command_;

  auto set = [this](std::size_t p, unsigned v) { values_[p] = Value{std::int64_t{v}}; };
  if (last_) {
    set(pt::target_code, last_->target_code);
    values_[pt::target_rpm] = Value{std::int64_t{rpm_of_code(last_->target_code)}};
    set(pt::actual_code, last_->actual_code);
    set(pt::error_code, last_->error_code);
    set(pt::ipm_temperature, last_->ipm_temp_c);
    set(pt::info_1, last_->info[0]);
    set(pt::info_2, last_->info[1]);
    set(pt::info_3, last_->info[2]);
  }
  if (sent_code_) set(pt::sent_code, *sent_code_);
  const FixedCodeState fc = phase_ == Phase::ready              ? FixedCodeState::ok
                            : phase_ == Phase::fixed_code_error ? FixedCodeState::error
                                                                : FixedCodeState::unchecked;
  set(pt::fixed_code_state, static_cast<unsigned>(fc));
}

}  // namespace drivegate::mdriver
