// Writes. The protocol has one frame that carries everything, the run command with its target
// code (section 3 No.2), and the run reply echoes the target the driver took (R4). So a write
// that needs the line is in force once a run reply echoed the code that carried it; until then,
// and when it fails, the keep-alive carries the code in force as before. A setpoint while stopped
// needs no line (the protocol keeps no setpoint: the next run_forward carries it) and is in force
// at once.
#include <algorithm>

#include "driver.h"
#include "rpm_table.h"

namespace drivegate::mdriver {

Proposed Mdriver2400Driver::in_force() const {
  // 0 stands for "no setpoint yet": every setpoint the drive can take is 504 rpm or more.
  return {command_, setpoint_code_ ? rpm_of_code(*setpoint_code_) : 0};
}

// One part of a request, against the state the parts before it leave (check_in_order). The
// drive's own state (the handshake, a latched error) changes only with what the line brings, never
// with a part of a request, so it is judged as it is now.
WriteCheck Mdriver2400Driver::judge(const WriteOp& op, const Proposed& p) const {
  switch (op.target) {
    case WriteOp::Target::forward:  // only ever handed to a driver that forwards()
    case WriteOp::Target::point:
      return WriteCheck::invalid_value;  // no writable points of its own
    case WriteOp::Target::setpoint:
      // Section 3 No.2: 504 rpm (0x1C), the lowest running speed, up to the table's 2856 (0x9F).
      if (!code_for_rpm(op.rpm)) return WriteCheck::invalid_value;
      // While a run is in force the setpoint goes on the line, which needs the handshake done.
      if (is_run(p.command) && phase_ != Phase::ready) return WriteCheck::refused;
      return WriteCheck::ok;
    case WriteOp::Target::command:
      break;
  }
  if (op.command == Command::run_reverse) return WriteCheck::invalid_value;  // one direction
  if (phase_ != Phase::ready) return WriteCheck::refused;
  // A latched error keeps the motor stopped until reset (code 0x00): refuse rather than confirm a
  // run that will not happen. Without a setpoint there is nothing to run at.
  if (op.command == Command::run_forward && (device_error() || p.setpoint_rpm == 0)) {
    return WriteCheck::refused;
  }
  return WriteCheck::ok;
}

WriteCheck Mdriver2400Driver::check(std::span<const WriteOp> request) const {
  return check_in_order(request, in_force(),
                        [this](const WriteOp& op, const Proposed& p) { return judge(op, p); });
}

WriteStatus Mdriver2400Driver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  if (const auto no = refusal(judge(op, in_force()))) return *no;
  Pending w;
  if (op.target == WriteOp::Target::setpoint) {
    const std::uint8_t code = *code_for_rpm(op.rpm);  // judge() found it in range
    // Stopped with nothing on its way to the drive: stored, the next run_forward carries it.
    if (command_ != Command::run_forward && writes_.empty()) {
      setpoint_code_ = code;
      refresh();
      return WriteStatus::done;
    }
    // Running, or a write ahead of it may start or stop the motor: next_write() decides once it
    // is first in line.
    w.setpoint_code = code;
  } else {
    // judge() let no run_reverse through; quick_stop is the plain stop (README, "Commands").
    w.change = op.command == Command::run_forward   ? Change::run
               : op.command == Command::reset_fault ? Change::reset
                                                    : Change::stop;
    // A command decides the code the line carries: what still waits for the line would be
    // overtaken by it at once, so it fails now (the drive never saw it) and costs no frame.
    writes_.settle_unsent(WriteResult::no_response);
  }
  writes_.push(w, t, now + kConfirmDeadline);
  refresh();
  return WriteStatus::pending;
}

// The code that carries a write, worked out once it is first in line, from what is in force then
// (a write ahead of it may have been confirmed or failed meanwhile). Nothing: no frame to send.
std::optional<std::uint8_t> Mdriver2400Driver::code_of(const Pending& w) const {
  switch (w.change) {
    case Change::run:
      return setpoint_code_;  // apply() took it with one in force, and none is ever withdrawn
    case Change::stop:
      return kStopCode;
    case Change::reset:
      return kCodeResetStop;  // section 3 No.2: [00] error reset & stop
    case Change::setpoint:
      if (command_ == Command::run_forward) return w.setpoint_code;
      return std::nullopt;  // the motor is stopped: nothing to tell the drive yet
  }
  return std::nullopt;
}

// The run command of the first write waiting for the line. A setpoint that finds the motor
// stopped needs none and is in force at once.
std::optional<Exchange> Mdriver2400Driver::next_write(TimePoint now) {
  while (!writes_.empty() && !writes_.front().sent) {
    Writes::Entry& e = writes_.front();
    if (const auto code = code_of(e.job)) {
      e.sent = true;
      e.job.sent_code = *code;
      return run_exchange(*code, now);
    }
    const bool stored = e.job.change == Change::setpoint;
    if (stored) setpoint_code_ = e.job.setpoint_code;
    writes_.settle_front(stored ? WriteResult::ok : WriteResult::refused);
  }
  refresh();
  return std::nullopt;
}

// A run reply: the write on the line, if any, is in force when R4 echoes the code that carried it.
void Mdriver2400Driver::confirm(const RunReply& r) {
  if (!writes_.front_on_line()) return;  // the reply to a keep-alive
  const Writes::Entry e = writes_.take_front();
  const Pending& w = e.job;
  // Section 3 No.2: R4 is the target the driver holds. A run answered with an error code (R7)
  // will not run either: the error keeps the motor stopped until reset.
  const bool took = r.target_code == w.sent_code && !(w.change == Change::run && r.error_code != 0);
  if (!took) {
    writes_.settle(e, WriteResult::refused);
    return;
  }
  switch (w.change) {
    case Change::run:
      command_ = Command::run_forward;
      break;
    case Change::stop:
    case Change::reset:  // [00] resets AND stops
      command_ = Command::stop;
      break;
    case Change::setpoint:
      setpoint_code_ = w.setpoint_code;
      break;
  }
  writes_.settle(e, WriteResult::ok);
}

void Mdriver2400Driver::fail_sent(WriteResult r) {
  if (writes_.front_on_line()) writes_.settle_front(r);
}

}  // namespace drivegate::mdriver
