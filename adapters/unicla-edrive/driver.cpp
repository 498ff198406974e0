#include "driver.h"

#include <algorithm>
#include <cstdlib>

#include "faults.h"
#include "points.h"

namespace drivegate::unicla {

namespace {

// drivegate's choices where the document is silent (README.md, "Timing").
constexpr Millis kInterFrameGap{5};
constexpr Millis kMinCommTimeout{3000};
constexpr Millis kWriteTimeoutSlack{1000};
// A speed change counts as taken once the speed is within this of the target (or moving to it).
constexpr std::int32_t kSpeedToleranceRpm = 50;

bool accepts_start(std::uint8_t op) {
  const auto st = static_cast<OpState>(op);
  return is_running_state(op) || st == OpState::wait_compressor_safety ||
         st == OpState::wait_anti_short || st == OpState::oil_balance_required ||
         st == OpState::oil_balance_run_wait;
}

}  // namespace

EDriveDriver::EDriveDriver(std::uint8_t address, Millis poll_interval, Settings settings)
    : address_(address),
      poll_interval_(poll_interval),
      settings_(settings),
      points_(make_points()),
      values_(points_.size()) {}

DriverTraits EDriveDriver::traits() const {
  DriverTraits t;
  const Millis budget = 4 * poll_interval_ + settings_.attempts * settings_.reply_timeout;
  t.comm_timeout = std::max(kMinCommTimeout, budget);
  t.write_timeout = settings_.confirm_timeout + kWriteTimeoutSlack;
  t.inter_frame_gap = kInterFrameGap;
  return t;
}

Frame EDriveDriver::request(CommandByte cmd, MessageId id, Bytes payload) {
  Frame f;
  f.source = kMasterAddress;
  f.destination = address_;
  f.command = static_cast<std::uint8_t>(cmd);
  f.message_id = static_cast<std::uint8_t>(id);
  f.sequence = ++sequence_;  // "Inserted by master for its internal synchronisation"
  f.payload = std::move(payload);
  return f;
}

std::optional<Exchange> EDriveDriver::next_exchange(TimePoint now) {
  expire(now);
  if (run_write_ && !run_write_->sent) return send_write(*run_write_, now);
  if (ack_write_ && !ack_write_->sent) return send_write(*ack_write_, now);
  if (now < next_poll_) return std::nullopt;

  MessageId id = MessageId::status;
  if (phase_ == Phase::build_information) id = MessageId::build_information;
  if (phase_ == Phase::running_limits) id = MessageId::running_limits;
  const Frame f = request(CommandByte::read, id);
  awaiting_ = Awaiting{id, f.sequence};
  next_poll_ = now + poll_interval_;

  Exchange ex;
  ex.frame = encode(f);
  ex.reply = ReplyMode::expected;
  ex.timeout = settings_.reply_timeout;
  ex.attempts = settings_.attempts;
  ex.priority = Priority::poll;
  return ex;
}

Exchange EDriveDriver::send_write(PendingWrite& w, TimePoint now) {
  const Frame f = w.kind == WriteKind::run_state
                      ? request(CommandByte::write, MessageId::set_run_state, encode_speed(w.speed))
                      : request(CommandByte::write, MessageId::acknowledge_faults);
  w.sent = true;
  w.deadline = now + settings_.confirm_timeout;
  w.was_running = status_ && is_running_state(status_->op_state);
  w.rpm_at_send = status_ ? status_->rpm : 0;
  // The confirming status read goes out right after the write.
  next_poll_ = std::min(next_poll_, now);

  Exchange ex;
  ex.frame = encode(f);
  ex.reply = ReplyMode::none;  // "Write commands are not acknowledged"
  ex.timeout = settings_.reply_timeout;
  ex.attempts = 1;  // an identical resend of an unacknowledged write proves nothing
  ex.priority = Priority::command;
  return ex;
}

TimePoint EDriveDriver::wake_at() const {
  if ((run_write_ && !run_write_->sent) || (ack_write_ && !ack_write_->sent)) return TimePoint{};
  TimePoint wake = next_poll_;
  if (run_write_) wake = std::min(wake, run_write_->deadline);
  if (ack_write_) wake = std::min(wake, ack_write_->deadline);
  return wake;
}

RxVerdict EDriveDriver::on_receive(ByteView rx, TimePoint now) {
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
  // Another device's reply, a request on the line, or a reply to an earlier sequence number.
  if (!awaiting_ || f.destination != kMasterAddress || f.source != address_ ||
      f.command != static_cast<std::uint8_t>(CommandByte::read) ||
      f.message_id != static_cast<std::uint8_t>(awaiting_->id) ||
      f.sequence != awaiting_->sequence) {
    return {RxKind::foreign, d.consumed};
  }
  bool ok = false;
  apply(awaiting_->id, f, now, ok);
  if (!ok) return {RxKind::noise, d.consumed};  // checked frame, payload too short: ignore it
  awaiting_.reset();
  return {RxKind::reply, d.consumed};
}

void EDriveDriver::apply(MessageId id, const Frame& f, TimePoint now, bool& ok) {
  switch (id) {
    case MessageId::build_information:
      if (const auto b = parse_build_info(f.payload, settings_.byte_order)) {
        fill_build_info(values_, *b);
        build_speed_ = {b->min_speed, b->max_speed};
        phase_ = Phase::running_limits;
        next_poll_ = now;
        ok = true;
      }
      break;
    case MessageId::running_limits:
      if (const auto l = parse_running_limits(f.payload, settings_.byte_order)) {
        fill_running_limits(values_, *l);
        // The configured limits bound Set Run State; a drive reporting none falls back to the
        // compressor build's.
        limits_ = (l->min_speed == 0 && l->max_speed == 0)
                      ? build_speed_
                      : SpeedLimits{l->min_speed, l->max_speed};
        control_enabled_ = l->control_enabled;
        phase_ = Phase::polling;
        next_poll_ = now;
        ok = true;
      }
      break;
    case MessageId::status:
      if (const auto s = parse_status(f.payload, settings_.byte_order)) {
        apply_status(*s);
        // Online only once the status, the data a PLC reads, is there too.
        common_.ready = phase_ == Phase::polling;
        ok = true;
      }
      break;
    default:
      break;
  }
}

void EDriveDriver::apply_status(const Status& s) {
  status_ = s;
  fill_status(values_, s);
  const FaultView fv = map_faults(s);
  common_.faults = fv.faults;
  common_.warning = fv.warning;
  common_.native_fault = fv.native;
  common_.speed_rpm = s.rpm;
  common_.running = is_running_state(s.op_state) || s.rpm > 0;
  confirm(run_write_, s);
  confirm(ack_write_, s);
}

void EDriveDriver::confirm(std::optional<PendingWrite>& w, const Status& s) {
  if (!w || !w->sent) return;
  w->saw_status = true;
  const std::uint8_t op = s.op_state;
  if (w->kind == WriteKind::acknowledge) {
    if (!is_fault_state(op)) finish(w, WriteResult::ok);
    return;
  }
  if (w->speed == 0) {
    if (!is_running_state(op)) finish(w, WriteResult::ok);
    return;
  }
  if (refuses_run(op)) {
    finish(w, WriteResult::refused);
    return;
  }
  if (!w->was_running) {
    if (accepts_start(op)) finish(w, WriteResult::ok);
    return;
  }
  // A speed change: the status has no setpoint echo, so the speed itself must show it.
  const std::int32_t target = w->speed;
  const std::int32_t off_now = std::abs(static_cast<std::int32_t>(s.rpm) - target);
  const std::int32_t off_before = std::abs(w->rpm_at_send - target);
  if (is_running_state(op) && (off_now <= kSpeedToleranceRpm || off_now < off_before)) {
    finish(w, WriteResult::ok);
  }
}

void EDriveDriver::finish(std::optional<PendingWrite>& w, WriteResult r) {
  for (const Ticket t : w->tickets) completions_.push_back({t, r});
  if (w->kind == WriteKind::run_state && r != WriteResult::ok) {
    common_.command = w->previous;
  }
  w.reset();
}

void EDriveDriver::expire(TimePoint now) {
  if (run_write_ && run_write_->sent && now >= run_write_->deadline) {
    finish(run_write_, WriteResult::no_response);
  }
  if (ack_write_ && ack_write_->sent && now >= ack_write_->deadline) {
    // Statuses came back but the fault stands: the drive did not take the acknowledgement.
    finish(ack_write_, ack_write_->saw_status ? WriteResult::refused : WriteResult::no_response);
  }
}

void EDriveDriver::on_no_reply(TimePoint /*now*/) {
  awaiting_.reset();
}

void EDriveDriver::on_comm_lost(TimePoint now) {
  awaiting_.reset();
  phase_ = Phase::build_information;
  common_.ready = false;
  limits_.reset();
  control_enabled_.reset();
  next_poll_ = std::min(next_poll_, now);
  if (run_write_) finish(run_write_, WriteResult::no_response);
  if (ack_write_) finish(ack_write_, WriteResult::no_response);
}

bool EDriveDriver::control_disabled() const {
  return control_enabled_.has_value() && *control_enabled_ == 0;
}

WriteStatus EDriveDriver::queue_run_state(std::uint16_t speed, Command previous, Ticket t) {
  PendingWrite w;
  if (run_write_) {
    // The command in force to restore on failure is the one before the unconfirmed write.
    previous = run_write_->previous;
    if ((run_write_->speed == 0) == (speed == 0)) {
      // The same request (run / run, stop / stop; e.g. setpoint and run_forward in one Modbus
      // write): the new frame carries it out too, so it waits with the new one.
      w.tickets = std::move(run_write_->tickets);
    } else {
      // The opposite request: superseded. It fails without touching the command in force,
      // which is already the new write's.
      for (const Ticket old : run_write_->tickets) {
        completions_.push_back({old, WriteResult::no_response});
      }
    }
    run_write_.reset();
  }
  w.kind = WriteKind::run_state;
  w.tickets.push_back(t);
  w.speed = speed;
  w.previous = previous;
  run_write_ = w;
  return WriteStatus::pending;
}

WriteStatus EDriveDriver::command(Command c, Ticket t, TimePoint /*now*/) {
  const Command previous = common_.command;
  switch (c) {
    case Command::run_reverse:
      return WriteStatus::invalid_value;  // a compressor turns one way
    case Command::stop:
    case Command::quick_stop:  // the protocol has no faster stop than Set Run State 0
      if (control_disabled()) return WriteStatus::refused;
      common_.command = Command::stop;
      return queue_run_state(0, previous, t);
    case Command::run_forward: {
      if (!limits_ || control_disabled()) return WriteStatus::refused;
      const std::int32_t sp = common_.setpoint_rpm;
      if (sp < limits_->min || sp > limits_->max || sp == 0) return WriteStatus::invalid_value;
      common_.command = Command::run_forward;
      return queue_run_state(static_cast<std::uint16_t>(sp), previous, t);
    }
    case Command::reset_fault: {
      if (control_disabled()) return WriteStatus::refused;
      if (ack_write_) finish(ack_write_, WriteResult::no_response);  // superseded
      PendingWrite w;
      w.kind = WriteKind::acknowledge;
      w.tickets = {t};
      ack_write_ = w;
      return WriteStatus::pending;
    }
  }
  return WriteStatus::invalid_value;
}

WriteStatus EDriveDriver::setpoint(std::int32_t rpm, Ticket t, TimePoint /*now*/) {
  if (rpm < 0) return WriteStatus::invalid_value;
  if (rpm > 0) {
    if (!limits_) return WriteStatus::refused;  // limits not read yet: cannot judge it
    if (rpm < limits_->min || rpm > limits_->max) return WriteStatus::invalid_value;
  }
  if (common_.command != Command::run_forward) {
    common_.setpoint_rpm = rpm;
    return WriteStatus::done;  // used by the next run_forward
  }
  if (control_disabled()) return WriteStatus::refused;
  common_.setpoint_rpm = rpm;
  const Command previous = common_.command;
  if (rpm == 0) common_.command = Command::stop;  // "a value of 0 is treated as a stop command"
  return queue_run_state(static_cast<std::uint16_t>(rpm), previous, t);
}

WriteStatus EDriveDriver::write(std::size_t /*point*/, const Value& /*v*/, Ticket /*t*/,
                                TimePoint /*now*/) {
  return WriteStatus::invalid_value;  // every adapter point is read-only
}

void EDriveDriver::take_completions(std::vector<Completion>& out) {
  out.insert(out.end(), completions_.begin(), completions_.end());
  completions_.clear();
}

}  // namespace drivegate::unicla
