#include "driver.h"

#include <algorithm>

#include "error_codes.h"
#include "rpm_table.h"

namespace drivegate::mdriver {

MDriver::MDriver(const Config& config, Millis poll_interval)
    : cfg_(config),
      // The run command is both poll and keep-alive (issue 4): every min(poll, keep-alive).
      cadence_(poll_interval.count() > 0 ? std::min(poll_interval, config.keepalive)
                                         : config.keepalive),
      points_(make_points()),
      values_(points_.size()) {
  refresh();
}

DriverTraits MDriver::traits() const {
  DriverTraits t;
  // Error table, 0x0C: the driver itself stops after 6 s without a frame from the master.
  t.comm_timeout = Millis(6000);
  t.write_timeout = Millis(3000);
  // Not in the document: 10 ms is 2.4 characters at 2400 baud.
  t.inter_frame_gap = Millis(10);
  return t;
}

std::uint8_t MDriver::target_code() const {
  if (reset_requested_) return kCodeResetStop;
  if (command_ == Command::run_forward && setpoint_code_) return *setpoint_code_;
  return kStopCode;
}

bool MDriver::device_error() const {
  return last_ && last_->error_code != 0;
}

bool MDriver::has_unsent() const {
  return std::any_of(pending_.begin(), pending_.end(),
                     [](const Pending& p) { return !p.in_flight; });
}

Exchange MDriver::make_exchange(Wire frame, Priority p) const {
  Exchange ex;
  ex.frame = std::move(frame);
  ex.reply = ReplyMode::expected;
  ex.timeout = kReplyTimeout;
  ex.attempts = kAttempts;
  ex.priority = p;
  return ex;
}

std::optional<Exchange> MDriver::next_exchange(TimePoint now) {
  expire(now);
  if (awaiting_ != Awaiting::nothing) return std::nullopt;
  if (phase_ != Phase::ready) {
    // Section 3 No.1: sent after power-up and resent until the driver answers.
    if (now < next_due_) return std::nullopt;
    next_due_ = now + cadence_;
    awaiting_ = Awaiting::check;
    return make_exchange(encode_check(cfg_.master, cfg_.device), Priority::poll);
  }
  const bool urgent = has_unsent();
  if (!urgent && now < next_due_) return std::nullopt;
  const std::uint8_t code = target_code();
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (!it->in_flight && it->code != code) {
      // Superseded by a later write before it reached the wire: never confirmed.
      done_.push_back({it->ticket, WriteResult::no_response});
      it = pending_.erase(it);
      continue;
    }
    it->in_flight = true;
    ++it;
  }
  sent_code_ = code;
  next_due_ = now + cadence_;
  awaiting_ = Awaiting::run;
  refresh();
  return make_exchange(encode_run(cfg_.master, cfg_.device, code, cfg_.change),
                       urgent ? Priority::command : Priority::poll);
}

TimePoint MDriver::wake_at() const {
  if (phase_ == Phase::ready && has_unsent()) return TimePoint{};
  TimePoint t = next_due_;
  for (const auto& p : pending_) t = std::min(t, p.deadline);
  return t;
}

RxVerdict MDriver::on_receive(ByteView rx, TimePoint now) {
  expire(now);
  const Decoded<Frame> d = decode(rx);
  switch (d.status) {
    case DecodeStatus::incomplete:
      return {RxKind::incomplete, 0};
    case DecodeStatus::bad:
      return damaged(d);
    case DecodeStatus::frame:
      break;
  }
  const Frame& f = d.frame;
  // Section 2: the driver answers with its own address as source, the master's as destination.
  if (f.src != cfg_.device || f.dst != cfg_.master) return {RxKind::foreign, d.consumed};
  RxKind kind = RxKind::foreign;
  if (awaiting_ == Awaiting::check && f.cmd == static_cast<std::uint8_t>(Cmd::check)) {
    kind = on_check_reply(f, now);
  } else if (awaiting_ == Awaiting::run && f.cmd == static_cast<std::uint8_t>(Cmd::run)) {
    kind = on_run_reply(f);
  }
  refresh();
  return {kind, d.consumed};
}

RxKind MDriver::on_check_reply(const Frame& f, TimePoint now) {
  const auto code = parse_check(f);
  if (!code) return RxKind::noise;
  awaiting_ = Awaiting::nothing;
  if (*code == kFixedCode) {
    phase_ = Phase::ready;
    next_due_ = now;  // first run command (status) at once
  } else {
    // Section 3 No.1: 00 00 00 00 = EEPROM check failed or code mismatch. Any other answer is
    // not the echo either: the same fault. Keep checking at the poll cadence.
    phase_ = Phase::fixed_code_error;
  }
  return RxKind::reply;
}

RxKind MDriver::on_run_reply(const Frame& f) {
  const auto r = parse_run_reply(f);
  if (!r) return RxKind::noise;
  awaiting_ = Awaiting::nothing;
  last_ = *r;
  // Confirmation: R4 echoes the D4 the driver took.
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (!it->in_flight) {
      ++it;
      continue;
    }
    done_.push_back(
        {it->ticket, r->target_code == it->code ? WriteResult::ok : WriteResult::refused});
    it = pending_.erase(it);
  }
  if (reset_requested_ && sent_code_ == kCodeResetStop) reset_requested_ = false;
  return RxKind::reply;
}

void MDriver::on_no_reply(TimePoint /*now*/) {
  awaiting_ = Awaiting::nothing;
  finish_in_flight(WriteResult::no_response);
  if (sent_code_ == kCodeResetStop) reset_requested_ = false;
  refresh();
}

void MDriver::on_comm_lost(TimePoint now) {
  // Forget the handshake: the driver may have been powered off; check the fixed code again.
  phase_ = Phase::check;
  awaiting_ = Awaiting::nothing;
  next_due_ = now;
  reset_requested_ = false;
  fail_all();
  refresh();
}

WriteStatus MDriver::command(Command c, Ticket t, TimePoint now) {
  if (c == Command::run_reverse) return WriteStatus::invalid_value;  // one direction only
  if (phase_ != Phase::ready) return WriteStatus::refused;
  switch (c) {
    case Command::run_forward:
      // A latched error keeps the motor stopped until reset (code 0x00): refuse rather than
      // confirm a run that will not happen. No setpoint yet: nothing to run at.
      if (device_error() || !setpoint_code_) return WriteStatus::refused;
      command_ = Command::run_forward;
      reset_requested_ = false;
      return queue(t, *setpoint_code_, now);
    case Command::stop:
    case Command::quick_stop:  // the protocol has one stop: the fixed ramp to a stop code
      command_ = Command::stop;
      reset_requested_ = false;
      return queue(t, kStopCode, now);
    case Command::reset_fault:
      command_ = Command::stop;  // 0x00 = error reset AND stop
      reset_requested_ = true;
      return queue(t, kCodeResetStop, now);
    case Command::run_reverse:
      break;
  }
  return WriteStatus::invalid_value;
}

WriteStatus MDriver::setpoint(std::int32_t rpm, Ticket t, TimePoint now) {
  const auto code = code_for_rpm(rpm);
  if (!code) return WriteStatus::invalid_value;
  setpoint_code_ = *code;
  if (phase_ == Phase::ready && command_ == Command::run_forward && !reset_requested_) {
    return queue(t, *code, now);
  }
  refresh();
  return WriteStatus::done;  // stored: the next run_forward uses it
}

WriteStatus MDriver::write(std::size_t, const Value&, Ticket, TimePoint) {
  return WriteStatus::invalid_value;  // no writable points of its own
}

void MDriver::take_completions(std::vector<Completion>& out) {
  out.insert(out.end(), done_.begin(), done_.end());
  done_.clear();
}

WriteStatus MDriver::queue(Ticket t, std::uint8_t code, TimePoint now) {
  pending_.push_back({t, code, now + kConfirmDeadline, false});
  refresh();
  return WriteStatus::pending;
}

void MDriver::finish_in_flight(WriteResult r) {
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (it->in_flight) {
      done_.push_back({it->ticket, r});
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
}

void MDriver::fail_all() {
  for (const auto& p : pending_) done_.push_back({p.ticket, WriteResult::no_response});
  pending_.clear();
}

void MDriver::expire(TimePoint now) {
  for (auto it = pending_.begin(); it != pending_.end();) {
    if (now >= it->deadline) {
      done_.push_back({it->ticket, WriteResult::no_response});
      it = pending_.erase(it);
    } else {
      ++it;
    }
  }
}

void MDriver::refresh() {
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

  auto set = [this](Pt p, Value v) { values_[static_cast<std::size_t>(p)] = std::move(v); };
  auto i64 = [](unsigned v) { return Value{static_cast<std::int64_t>(v)}; };
  if (last_) {
    set(Pt::target_code, i64(last_->target_code));
    set(Pt::target_rpm, Value{std::int64_t{rpm_of_code(last_->target_code)}});
    set(Pt::actual_code, i64(last_->actual_code));
    set(Pt::error_code, i64(last_->error_code));
    set(Pt::ipm_temperature, i64(last_->ipm_temp_c));
    set(Pt::info_1, i64(last_->info[0]));
    set(Pt::info_2, i64(last_->info[1]));
    set(Pt::info_3, i64(last_->info[2]));
  }
  if (sent_code_) set(Pt::sent_code, i64(*sent_code_));
  const FixedCodeState fc = phase_ == Phase::ready              ? FixedCodeState::ok
                            : phase_ == Phase::fixed_code_error ? FixedCodeState::error
                                                                : FixedCodeState::unchecked;
  set(Pt::fixed_code_state, i64(static_cast<unsigned>(fc)));
}

}  // namespace drivegate::mdriver
