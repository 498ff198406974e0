// Writes. The eDrive never acknowledges one ("Command": "Write commands are not acknowledged"), so
// a write that needs the line is in force once a status read after it shows the drive took it
// (README.md, "Writes and their confirmation"): a run once the drive starts (or waits to), a stop
// once it no longer runs, a speed change once the speed comes to the new target, an acknowledge
// once no Fault-* state stands. Until then, and when the write fails (refused, not shown in time,
// superseded), `command` and `setpoint_rpm` read what was in force before. A setpoint written
// while no run is in force needs no line and is in force at once: the next run carries it.
#include <algorithm>
#include <cstdlib>

#include "driver.h"
#include "op_state.h"

namespace drivegate::unicla {

Proposed EDriveDriver::in_force() const {
  return {common_.command, common_.setpoint_rpm};
}

// Running Limits, "Control Enabled" = 0: the drive ignores the bus, so it would take no write.
bool EDriveDriver::control_disabled() const {
  return control_enabled_.has_value() && *control_enabled_ == 0;
}

// One part of a request, against what the parts before it leave in force (check_in_order). The
// limits and Control Enabled change only with what the line brings (a comm loss and the reads
// after it), never with a part of a request, so they are judged as they are now.
WriteCheck EDriveDriver::judge(const WriteOp& op, const Proposed& p) const {
  switch (op.target) {
    case WriteOp::Target::forward:  // only ever handed to a driver that forwards()
    case WriteOp::Target::point:
      return WriteCheck::invalid_value;  // every point of its own is read-only
    case WriteOp::Target::setpoint:
      // "Set Run State": an unsigned 16-bit speed, 0 = stop, else "between the configured min and
      // max reported by eDrive": until the limits are read it cannot be judged.
      if (op.rpm < 0) return WriteCheck::invalid_value;
      if (op.rpm > 0) {
        if (!limits_) return WriteCheck::refused;
        if (op.rpm < limits_->min || op.rpm > limits_->max) return WriteCheck::invalid_value;
      }
      // While a run is in force the setpoint goes on the line, which the drive would ignore.
      if (is_run(p.command) && control_disabled()) return WriteCheck::refused;
      return WriteCheck::ok;
    case WriteOp::Target::command:
      break;
  }
  switch (op.command) {
    case Command::run_reverse:
      return WriteCheck::invalid_value;  // a compressor turns one way: Set Run State has no sign
    case Command::run_forward:
      if (!limits_ || control_disabled()) return WriteCheck::refused;
      // Set Run State 0 would be a stop: there is nothing to run at.
      if (p.setpoint_rpm == 0 || p.setpoint_rpm < limits_->min || p.setpoint_rpm > limits_->max) {
        return WriteCheck::invalid_value;
      }
      return WriteCheck::ok;
    case Command::stop:
    case Command::quick_stop:
    case Command::reset_fault:
      return control_disabled() ? WriteCheck::refused : WriteCheck::ok;
  }
  return WriteCheck::invalid_value;
}

WriteCheck EDriveDriver::check(std::span<const WriteOp> request) const {
  return check_in_order(request, in_force(),
                        [this](const WriteOp& op, const Proposed& p) { return judge(op, p); });
}

WriteStatus EDriveDriver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  adopting_ = false;  // a client decides from now on
  if (const auto no = refusal(judge(op, in_force()))) return *no;
  // judge() let no point through, and a setpoint of 0..65535 only.
  if (op.target == WriteOp::Target::setpoint) {
    return apply_setpoint(static_cast<std::uint16_t>(op.rpm), t, now);
  }
  switch (op.command) {
    case Command::run_forward:
      // Running at the setpoint in force already: there is nothing to tell the drive (a PLC that
      // writes "setpoint, run" every cycle costs no frame).
      if (run_writes_.empty() && common_.command == Command::run_forward && drive_runs()) {
        return WriteStatus::done;
      }
      return apply_run_state(Change::run, static_cast<std::uint16_t>(common_.setpoint_rpm), t, now);
    case Command::stop:
    case Command::quick_stop:
      // The protocol has no faster stop than Set Run State 0. A stop always goes on the line: the
      // drive may run for reasons the gateway did not give it (eConnect, a run it took unseen).
      return apply_run_state(Change::stop, 0, t, now);
    case Command::reset_fault:
      return apply_acknowledge(t, now);
    case Command::run_reverse:
      break;  // judge() let none through
  }
  return WriteStatus::invalid_value;
}

WriteStatus EDriveDriver::apply_setpoint(std::uint16_t rpm, Ticket t, TimePoint now) {
  if (run_writes_.empty() && (!is_run(common_.command) || rpm == common_.setpoint_rpm)) {
    // No run in force: stored, the next run_forward carries it. The speed in force: nothing to
    // send.
    common_.setpoint_rpm = rpm;
    return WriteStatus::done;
  }
  // A run is in force, or a Set Run State ahead of it may yet start or stop the drive: its turn
  // decides (settle_front()).
  if (!join(Change::speed, rpm, t)) {
    run_writes_.push(make_pending(Change::speed, rpm), t, deadline_from(now));
  }
  return WriteStatus::pending;
}

WriteStatus EDriveDriver::apply_run_state(Change change, std::uint16_t rpm, Ticket t,
                                          TimePoint now) {
  if (join(change, rpm, t)) return WriteStatus::pending;
  // A command decides what the drive is to do: a Set Run State not yet confirmed is overtaken by
  // it and fails, in force or not, whether or not it reached the drive.
  run_writes_.settle_all(WriteResult::no_response);
  run_writes_.push(make_pending(change, rpm), t, deadline_from(now));
  return WriteStatus::pending;
}

WriteStatus EDriveDriver::apply_acknowledge(Ticket t, TimePoint now) {
  // A second acknowledge overtakes the first with a frame of its own: the condition behind the
  // fault may have gone since the first went out.
  settle_ack(WriteResult::no_response);
  ack_ = Writes::Entry{make_pending(Change::acknowledge, 0), {t}, deadline_from(now)};
  return WriteStatus::pending;
}

EDriveDriver::Pending EDriveDriver::make_pending(Change change, std::uint16_t rpm) {
  Pending w;
  w.change = change;
  w.rpm = rpm;
  w.order = next_order_++;
  return w;
}

// From when it was applied, not sent: a write queued behind another is decided in time too.
TimePoint EDriveDriver::deadline_from(TimePoint now) const {
  return now + settings_.confirm_timeout;
}

// A write asking exactly what the last unconfirmed Set Run State asks waits for the same status
// instead of a frame of its own, and gets the same verdict.
bool EDriveDriver::join(Change change, std::uint16_t rpm, Ticket t) {
  if (run_writes_.empty()) return false;
  Writes::Entry& last = run_writes_.back();
  if (last.job.change != change || last.job.rpm != rpm) return false;
  run_writes_.join(last, t);
  return true;
}

bool EDriveDriver::has_unsent_write() const {
  return (!run_writes_.empty() && !run_writes_.front().sent) || (ack_ && !ack_->sent);
}

bool EDriveDriver::awaiting_confirmation() const {
  return run_writes_.front_on_line() || (ack_ && ack_->sent);
}

TimePoint EDriveDriver::earliest_deadline() const {
  TimePoint t = run_writes_.next_deadline().value_or(TimePoint::max());
  if (ack_) t = std::min(t, ack_->deadline);
  return t;
}

// The frame of the write applied first among those waiting for the line; a Set Run State goes out
// only once the one before it was decided.
std::optional<Exchange> EDriveDriver::next_write(TimePoint now) {
  settle_front();
  Writes::Entry* run =
      !run_writes_.empty() && !run_writes_.front().sent ? &run_writes_.front() : nullptr;
  Writes::Entry* ack = ack_ && !ack_->sent ? &*ack_ : nullptr;
  if (run != nullptr && ack != nullptr && ack->job.order < run->job.order) run = nullptr;
  if (run != nullptr) return send(*run, now);
  if (ack != nullptr) return send(*ack, now);
  return std::nullopt;
}

Exchange EDriveDriver::send(Writes::Entry& e, TimePoint now) {
  Pending& w = e.job;
  const Frame f = w.change == Change::acknowledge
                      ? request(CommandByte::write, MessageId::acknowledge_faults)  // "Payload: 0"
                      : request(CommandByte::write, MessageId::set_run_state, encode_speed(w.rpm));
  e.sent = true;
  w.was_running = drive_runs();
  w.rpm_at_send = status_ ? status_->rpm : 0;
  // The status read that may confirm it goes out right after it.
  next_poll_ = std::min(next_poll_, now);

  Exchange ex;
  ex.frame = encode(f);
  ex.reply = ReplyMode::none;  // "Write commands are not acknowledged"
  ex.timeout = settings_.reply_timeout;
  ex.attempts = 1;  // an identical resend of an unacknowledged write proves nothing
  return ex;
}

// A setpoint whose turn came with no run in force (the Set Run State before it stopped, or
// failed), or at the speed in force, needs no frame: in force at once.
void EDriveDriver::settle_front() {
  while (!run_writes_.empty()) {
    const Writes::Entry& e = run_writes_.front();
    if (e.sent || e.job.change != Change::speed) return;
    if (is_run(common_.command) && e.job.rpm != common_.setpoint_rpm) return;
    common_.setpoint_rpm = e.job.rpm;
    run_writes_.settle_front(WriteResult::ok);
  }
}

// A status read after a write went out: the drive took it, refused it, or has not shown yet.
void EDriveDriver::confirm(const Status& s, TimePoint now) {
  if (run_writes_.front_on_line()) {
    Pending& w = run_writes_.front().job;
    w.saw_status = true;
    if (const auto r = verdict(w, s)) {
      if (*r == WriteResult::ok) take_effect(w);
      finish_front(*r, now);
    }
  }
  if (ack_ && ack_->sent) {
    ack_->job.saw_status = true;
    if (!is_fault_state(s.op_state)) settle_ack(WriteResult::ok);
  }
}

std::optional<WriteResult> EDriveDriver::verdict(const Pending& w, const Status& s) const {
  const std::uint8_t op = s.op_state;
  // "Sending a value of 0 is treated as a stop command": taken once the drive no longer runs.
  if (w.rpm == 0) {
    if (is_running_state(op)) return std::nullopt;
    return WriteResult::ok;
  }
  if (refuses_run(op)) return WriteResult::refused;
  if (w.change == Change::run && !w.was_running) {
    if (took_run(op)) return WriteResult::ok;
    return std::nullopt;
  }
  // A speed change (or a run sent to a drive that ran): the status has no setpoint echo, so the
  // speed itself must show it.
  const std::int32_t target = w.rpm;
  const std::int32_t off_now = std::abs(static_cast<std::int32_t>(s.rpm) - target);
  const std::int32_t off_before = std::abs(w.rpm_at_send - target);
  if (is_running_state(op) && (off_now <= kSpeedToleranceRpm || off_now < off_before)) {
    return WriteResult::ok;
  }
  return std::nullopt;
}

void EDriveDriver::take_effect(const Pending& w) {
  switch (w.change) {
    case Change::run:
      common_.command = Command::run_forward;
      common_.setpoint_rpm = w.rpm;
      break;
    case Change::stop:
      common_.command = Command::stop;
      break;
    case Change::speed:
      common_.setpoint_rpm = w.rpm;
      if (w.rpm == 0) common_.command = Command::stop;  // "treated as a stop command"
      break;
    case Change::acknowledge:
      break;
  }
}

// The Set Run State on the line is decided. A run that failed while no run is in force is undone
// with a Set Run State 0 of the driver's own: the drive may have taken it unseen, or may act on it
// once the fault that refused it clears, and the PLC was told it did not happen.
void EDriveDriver::finish_front(WriteResult r, TimePoint now) {
  const Writes::Entry w = run_writes_.take_front();
  run_writes_.settle(w, r);
  if (r != WriteResult::ok && w.job.change == Change::run && !is_run(common_.command)) {
    run_writes_.push_front(make_pending(Change::stop, 0), {}, deadline_from(now));
  }
}

void EDriveDriver::settle_ack(WriteResult r) {
  if (ack_) run_writes_.settle(*ack_, r);
  ack_.reset();
}

// Writes the drive has not shown it took within confirm_timeout fail: "did not take it in time".
// Only the front is ever on the line: it is decided first (a failed run is undone), then those
// still waiting.
void EDriveDriver::expire(TimePoint now) {
  if (run_writes_.front_on_line() && run_writes_.front().deadline <= now) {
    finish_front(WriteResult::no_response, now);
  }
  run_writes_.settle_if([now](const Writes::Entry& e) { return !e.sent && e.deadline <= now; },
                        WriteResult::no_response);
  if (ack_ && now >= ack_->deadline) {
    // Statuses came back and the fault still stands: the drive did not take the acknowledge.
    settle_ack(ack_->job.saw_status ? WriteResult::refused : WriteResult::no_response);
  }
}

void EDriveDriver::fail_all() {
  run_writes_.settle_all(WriteResult::no_response);
  settle_ack(WriteResult::no_response);
}

}  // namespace drivegate::unicla
