// Writes of command and setpoint (slave mode only; outside it IN1 / IN2 and the thermostat set the
// speed and the line only monitors). The speed frame carries the whole order, command and
// setpoint, and the controller never acknowledges it (INPUT, Programming speed); the specs README
// says to confirm it through the streamed status. So:
//
//  - in force (what common() shows) is only what the stream confirmed: motor ON for a run, within
//    tolerance_rpm of the setpoint for a speed change, motor OFF for a stop; and a setpoint
//    written while stopped, which needs no line and is stored at once;
//  - the frames (the write's own, and the refresh while it waits) carry the order of the write
//    under way: sending the order in force instead would undo the very write being confirmed;
//  - a write that fails (an alarm in the stream: refused; not shown within confirm_ms, superseded
//    or comm_lost: no_response) leaves in force what was, and the controller is told that again
//    at once if a frame of the failed write went out, so that a run the PLC was told failed does
//    not start the compressor later (when an alarm clears, or when its restart delay ends).
#include <cstdlib>

#include "driver.h"

namespace drivegate::fdc1 {

Proposed Fdc1Driver::in_force() const {
  return {in_force_.command, in_force_.setpoint};
}

// One command or setpoint part against what the parts before it leave in force (check_in_order).
// The controller's own state (an alarm, a restart delay) is not judged here: only the stream can
// say whether it takes a run, so such a run is sent and refused from the stream.
WriteCheck Fdc1Driver::judge(const WriteOp& op, const Proposed& p) const {
  switch (op.target) {
    case WriteOp::Target::forward:  // only ever handed to a driver that forwards()
    case WriteOp::Target::point:
      return WriteCheck::invalid_value;  // judge_point() judges those
    case WriteOp::Target::setpoint:
      if (!settings_.slave_mode) return WriteCheck::invalid_value;  // IN1 / IN2 set the speed
      // INPUT, Programming speed: 1500..3500 rpm; 0 is a stop, which is a command here.
      if (op.rpm < kMinRpm || op.rpm > kMaxRpm) return WriteCheck::invalid_value;
      return WriteCheck::ok;
    case WriteOp::Target::command:
      break;
  }
  // A compressor turns one way, and the protocol has no fault reset (alarms clear by themselves
  // or end in "end of retries").
  if (op.command == Command::run_reverse || op.command == Command::reset_fault) {
    return WriteCheck::invalid_value;
  }
  if (!settings_.slave_mode) return WriteCheck::invalid_value;
  if (op.command == Command::run_forward && p.setpoint_rpm == 0) return WriteCheck::refused;
  return WriteCheck::ok;
}

WriteCheck Fdc1Driver::check(std::span<const WriteOp> request) const {
  // The programming fields as the parts before each part leave them: a commit in the same request
  // as its fields is judged on them. A local copy: check() changes nothing.
  std::vector<Value> fields = values_;
  return check_in_order(request, in_force(), [&](const WriteOp& op, const Proposed& p) {
    if (op.target != WriteOp::Target::point) return judge(op, p);
    const WriteCheck c = judge_point(op, fields);
    if (c == WriteCheck::ok && is_program_field(op.point)) store_field(op, fields);
    return c;
  });
}

WriteStatus Fdc1Driver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  if (op.target == WriteOp::Target::point) return apply_point(op, t, now);
  adopting_ = false;  // a client decides from now on
  if (const auto no = refusal(judge(op, in_force()))) return *no;
  return op.target == WriteOp::Target::setpoint ? apply_setpoint(op.rpm, t, now)
                                                : apply_command(op.command, t, now);
}

WriteStatus Fdc1Driver::apply_setpoint(std::int32_t rpm, Ticket t, TimePoint now) {
  const Order line = on_line();
  // Stopped, and no run under way: stored, the next run_forward carries it. A stop under way
  // carries it too (its frame does not depend on it).
  if (!is_run(in_force_.command) && !is_run(line.command)) {
    in_force_.setpoint = rpm;
    if (write_) write_->order.setpoint = rpm;
    publish_common();
    return WriteStatus::done;
  }
  // A run in force or under way: a speed change, in force at that speed. A stop under way while
  // the motor runs: the setpoint waits with it, and is stored once the stream shows the motor off.
  const Expect e = is_run(line.command) ? Expect::at_setpoint : Expect::motor_off;
  return start_write(Asked{t, rpm}, Order{line.command, rpm}, e, now);
}

WriteStatus Fdc1Driver::apply_command(Command c, Ticket t, TimePoint now) {
  const bool runs = is_run(c);  // judge() let only run_forward through
  // A write under way in the same direction is carried by the same frame, with its setpoint;
  // otherwise the run is at the setpoint in force. quick_stop is a plain stop: the protocol has
  // nothing faster than speed 0.
  const Order base = write_ && is_run(write_->order.command) == runs ? write_->order : in_force_;
  const Expect e = runs ? Expect::motor_on : Expect::motor_off;
  return start_write(Asked{t, std::nullopt}, Order{c, base.setpoint}, e, now);
}

bool Fdc1Driver::shows(const Status& s, const Order& o, Expect e) const {
  switch (e) {
    case Expect::motor_off:
      return !s.motor_on;
    case Expect::motor_on:
      return s.motor_on;
    case Expect::at_setpoint:
      return s.motor_on && std::abs(s.rpm - o.setpoint) <= settings_.tolerance_rpm;
  }
  return false;
}

// Starts carrying out `order` for the write `a`, or takes it at once when nothing is under way,
// the frame would be the one in force and the latest status already shows it held: a PLC that
// rewrites its command every cycle then costs the line nothing.
WriteStatus Fdc1Driver::start_write(Asked a, Order order, Expect e, TimePoint now) {
  const bool same_frame = is_run(order.command) == is_run(in_force_.command) &&
                          (!is_run(order.command) || order.setpoint == in_force_.setpoint);
  if (!write_ && same_frame && last_status_ && shows(*last_status_, order, e)) {
    in_force_ = order;
    publish_common();
    return WriteStatus::done;
  }
  std::vector<Asked> asked;
  if (write_ && is_run(write_->order.command) == is_run(order.command)) {
    // The new frame carries out the commands under way, and the setpoints that asked its speed;
    // a setpoint that asked another speed is superseded (it is never in force).
    for (const Asked& w : write_->asked) {
      if (w.rpm && *w.rpm != order.setpoint) {
        completions_.add(w.ticket, WriteResult::no_response);
      } else {
        asked.push_back(w);
      }
    }
    if (write_->expect == Expect::at_setpoint) e = Expect::at_setpoint;
    write_.reset();
  } else if (write_) {
    fail_write(WriteResult::no_response, now);  // superseded: the PLC asked the opposite since
  }
  asked.push_back(a);
  write_ = SpeedWrite{std::move(asked), order, e, now + settings_.confirm, false};
  // Before the controller is first heard the write waits: the start-up sends it with the first
  // status, and comm_lost fails it if the controller never streams.
  send_soon(now);
  publish_common();
  return WriteStatus::pending;
}

void Fdc1Driver::confirm(const Status& s, TimePoint now) {
  if (!write_) return;
  if (shows(s, write_->order, write_->expect)) {
    in_force_ = write_->order;
    for (const Asked& w : write_->asked) completions_.add(w.ticket, WriteResult::ok);
    write_.reset();
    return;
  }
  // OUTPUT: an OFF frame with an alarm code: the motor will not run now, so a run or a speed
  // change is refused (a stop is shown by that very frame).
  if (!s.motor_on && s.alarm != 0 && write_->expect != Expect::motor_off) {
    fail_write(WriteResult::refused, now);
  }
}

void Fdc1Driver::fail_write(WriteResult r, TimePoint now) {
  const bool sent = write_->sent;
  for (const Asked& w : write_->asked) completions_.add(w.ticket, r);
  write_.reset();
  // In force is still what was. The controller may have acted on a frame of the failed write:
  // tell it what is in force, at once (after comm_lost the start-up does, once it streams again).
  if (sent && slave_ready()) send_soon(now);
  publish_common();
}

void Fdc1Driver::expire(TimePoint now) {
  if (write_ && now >= write_->deadline) fail_write(WriteResult::no_response, now);
}

}  // namespace drivegate::fdc1
