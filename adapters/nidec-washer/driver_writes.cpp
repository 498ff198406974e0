// NidecWasherDriver: Modbus writes judged whole (check), applied part by part (apply), queued as
// frames of section 5 and confirmed by their ACKs. What is in force (common().command,
// common().setpoint_rpm, the motion) changes only when the inverter has ACKed the frame that
// carries it without Error bits, or, for a setpoint written while no run is in force or on its
// way, when it is stored for the next run.
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <variant>

#include "driver.h"

namespace drivegate::nidec {
namespace {

// A queued write not confirmed by then fails with no_response and is dropped, before the
// gateway's own deadline (traits().write_timeout, 3 s) runs out: the inverter never acts on a
// write the PLC was told failed.
constexpr Millis kConfirmTimeout{2500};

// The whole number a write carries, in the frame's units (`factor` 10: 100 ms units of seconds).
std::optional<std::int64_t> whole(const Value& v, double factor) {
  if (std::holds_alternative<std::monostate>(v) || std::holds_alternative<std::string>(v)) {
    return std::nullopt;
  }
  return std::llround(as_double(v) * factor);
}

// Seconds points (accel and agitation times) travel in 100 ms units (5.3, 5.5).
double factor_of(std::size_t point) {
  return point == pt::accel_time || is_agitation_time(point) ? 10.0 : 1.0;
}

}  // namespace

// --- judging ---

NidecWasherDriver::Judged NidecWasherDriver::judged_now() const {
  return {motion_, common_.native_fault != 0, forced_brake_};
}

WriteCheck NidecWasherDriver::judge(const WriteOp& op, Judged& state) {
  switch (op.target) {
    case WriteOp::Target::command:
      switch (op.command) {
        case Command::stop:
        case Command::quick_stop:
          return WriteCheck::ok;
        case Command::reset_fault:
          // It succeeds only when the ACK shows no Error bits: a run after it meets no fault.
          state.faulted = false;
          return WriteCheck::ok;
        case Command::run_forward:
        case Command::run_reverse:
          // Only CW / CCW (5.3 / 5.4) have a direction; spin, agitation and free-shaft spin
          // (5.5, 5.6, 5.14) have none.
          if (op.command == Command::run_reverse && state.motion != Motion::rotation) {
            return WriteCheck::invalid_value;
          }
          // Section 8: a faulted inverter keeps the motor stopped; 5.13: so does the forced brake.
          if (state.faulted || state.forced_brake) return WriteCheck::refused;
          return WriteCheck::ok;
      }
      return WriteCheck::invalid_value;
    case WriteOp::Target::setpoint:
      // 5.3 - 5.6, 5.14: the speed is 16 bits, unsigned.
      return op.rpm < 0 || op.rpm > 0xFFFF ? WriteCheck::invalid_value : WriteCheck::ok;
    case WriteOp::Target::forward:  // only ever handed to a driver that forwards()
      return WriteCheck::invalid_value;
    case WriteOp::Target::point:
      break;
  }
  const std::optional<std::int64_t> n = whole(op.value, factor_of(op.point));
  if (!n || *n < 0) return WriteCheck::invalid_value;
  if (op.point == pt::motion) {
    if (*n >= static_cast<std::int64_t>(kMotionNames.size())) return WriteCheck::invalid_value;
    state.motion = static_cast<Motion>(*n);
    return WriteCheck::ok;
  }
  if (op.point == pt::accel_time) {
    return *n > 0xFFFF ? WriteCheck::invalid_value : WriteCheck::ok;  // 5.3: 16 bits
  }
  if (is_agitation_time(op.point)) {
    return *n > 0xFF ? WriteCheck::invalid_value : WriteCheck::ok;  // 5.5: one byte each
  }
  if (op.point == pt::action) {
    if (*n >= static_cast<std::int64_t>(kActionNames.size())) return WriteCheck::invalid_value;
    const auto a = static_cast<Action>(*n);
    if (a == Action::forced_brake_enable) state.forced_brake = true;
    if (a == Action::forced_brake_disable) state.forced_brake = false;
    return WriteCheck::ok;
  }
  return WriteCheck::invalid_value;  // an input point: the gateway never sends one
}

WriteCheck NidecWasherDriver::check(std::span<const WriteOp> request) const {
  // check_in_order() carries the setpoint and command, which no judgement here depends on; the
  // judge carries the rest a part leaves for the parts after it (the motion a run starts, the
  // fault a reset clears, the forced brake an action sets).
  Judged state = judged_now();
  return check_in_order(request, {common_.command, common_.setpoint_rpm},
                        [&state](const WriteOp& op, const Proposed&) { return judge(op, state); });
}

// --- applying ---

WriteStatus NidecWasherDriver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  // The judgement check() made, against what is in force now: a part is taken exactly when
  // check() said it would be, unless an ACK changed the drive's state in between.
  Judged state = judged_now();
  if (const auto no = refusal(judge(op, state))) return *no;
  const TimePoint deadline = now + kConfirmTimeout;
  switch (op.target) {
    case WriteOp::Target::command:
      return apply_command(op.command, t, deadline);
    case WriteOp::Target::setpoint:
      return apply_setpoint(static_cast<std::uint16_t>(op.rpm), t, deadline);
    case WriteOp::Target::point:
      return apply_point(op.point, op.value, t, deadline);
    case WriteOp::Target::forward:  // judge() refused it
      break;
  }
  return WriteStatus::invalid_value;
}

WriteStatus NidecWasherDriver::apply_command(Command c, Ticket t, TimePoint deadline) {
  switch (c) {
    case Command::stop:  // 5.7: closed-loop stop
      supersede_motion();
      return enqueue({.job = Job::stop, .command = c, .request = make_bare(Mode::stop)}, t,
                     deadline);
    case Command::quick_stop:  // 5.8: brake, open loop, as fast as possible
      supersede_motion();
      return enqueue({.job = Job::stop, .command = c, .request = make_bare(Mode::brake)}, t,
                     deadline);
    case Command::reset_fault:  // no reset frame: a Request (5.2) asks whether the fault cleared
      return enqueue({.job = Job::reset_fault, .request = make_bare(Mode::request)}, t, deadline);
    case Command::run_forward:
    case Command::run_reverse:
      // The frame is made when it reaches the line (front_to_send()).
      return enqueue({.job = Job::run, .command = c, .motion = motion_, .request = std::nullopt}, t,
                     deadline);
  }
  return WriteStatus::invalid_value;
}

WriteStatus NidecWasherDriver::apply_setpoint(std::uint16_t rpm, Ticket t, TimePoint deadline) {
  // No run in force and none on its way: stored, and the next run carries it.
  if (!is_run(common_.command) && !motion_queued()) {
    common_.setpoint_rpm = rpm;
    return WriteStatus::done;
  }
  // Otherwise the inverter is to take it: in force once it ACKed the frame that carries it.
  return enqueue({.job = Job::setpoint, .rpm = rpm, .request = std::nullopt}, t,
                 deadline);  // made when it reaches the line
}

WriteStatus NidecWasherDriver::apply_point(std::size_t point, const Value& v, Ticket t,
                                           TimePoint deadline) {
  const std::int64_t n = whole(v, factor_of(point)).value_or(0);  // judge() checked it
  if (point == pt::motion) {
    motion_ = static_cast<Motion>(n);
    values_[point] = n;
    return WriteStatus::done;
  }
  if (point == pt::accel_time) {
    accel_100ms_ = static_cast<std::uint16_t>(n);
    values_[point] = seconds_of(n);
    return WriteStatus::done;
  }
  if (is_agitation_time(point)) {
    // 5.5: accel, decel, CW on, CW off, CCW on, CCW off, in the points' order.
    const std::array<std::uint8_t*, 6> fields = {&agitation_.accel,  &agitation_.decel,
                                                 &agitation_.cw_on,  &agitation_.cw_off,
                                                 &agitation_.ccw_on, &agitation_.ccw_off};
    *fields[point - pt::agitation_accel] = static_cast<std::uint8_t>(n);
    values_[point] = seconds_of(n);
    return WriteStatus::done;
  }
  if (point == pt::action) return apply_action(static_cast<Action>(n), t, deadline);
  return WriteStatus::invalid_value;
}

WriteStatus NidecWasherDriver::apply_action(Action a, Ticket t, TimePoint deadline) {
  values_[pt::action] = std::int64_t{static_cast<std::int64_t>(a)};
  Request r;
  switch (a) {
    case Action::none:
      return WriteStatus::done;
    case Action::voltage_detection:
      r = make_bare(Mode::voltage_detection);
      break;
    case Action::weight_detection:
      r = make_bare(Mode::weight_detection);
      break;
    case Action::fabric_detection:
      r = make_bare(Mode::fabric_detection);  // 5.11: no layout: zero-filled
      break;
    case Action::forced_brake_enable:
      r = make_forced_brake(true);
      break;
    case Action::forced_brake_disable:
      r = make_forced_brake(false);
      break;
    case Action::fct_test:
      r = make_fct();
      break;
    case Action::ping:
      r = make_ping(settings_.platform, settings_.empty_raw_weight);
      break;
  }
  values_[pt::action_status] = std::int64_t{static_cast<std::int64_t>(ActionStatus::pending)};
  return enqueue({.job = Job::action, .request = r}, t, deadline);
}

// --- the queue ---

WriteStatus NidecWasherDriver::enqueue(Queued q, Ticket t, TimePoint deadline) {
  queue_.push(q, t, deadline);
  return WriteStatus::pending;
}

bool NidecWasherDriver::motion_queued() const {
  return std::any_of(queue_.begin(), queue_.end(), [](const Writes::Entry& e) {
    return e.job.job == Job::run || e.job.job == Job::setpoint;
  });
}

void NidecWasherDriver::supersede_motion() {
  // A stop overtakes the runs and speed changes queued before it that are not on the line right
  // now: they fail (0x0B) and leave what is in force, so the motor is not started only to be
  // stopped. The one on the line may have reached the inverter; the stop follows it.
  const Writes::Entry* on_line =
      in_flight_ == InFlight::queued && !queue_.empty() ? &queue_.front() : nullptr;
  queue_.settle_if(
      [on_line](const Writes::Entry& e) {
        return &e != on_line && (e.job.job == Job::run || e.job.job == Job::setpoint);
      },
      WriteResult::no_response);
}

std::optional<Request> NidecWasherDriver::run_request(Command c, Motion m,
                                                      std::uint16_t rpm) const {
  const bool reverse = c == Command::run_reverse;
  switch (m) {
    case Motion::rotation:
      return make_run(reverse ? Mode::ccw : Mode::cw, rpm, accel_100ms_);  // 5.3 / 5.4
    case Motion::spin:
      if (reverse) return std::nullopt;  // 5.6 has no direction
      return make_run(Mode::spin, rpm, accel_100ms_);
    case Motion::agitation:
      if (reverse) return std::nullopt;  // 5.5 alternates CW and CCW by itself
      return make_agitation(rpm, agitation_);
    case Motion::free_shaft_spin:
      if (reverse) return std::nullopt;  // 5.14 has no direction
      return make_run(Mode::free_shaft_spin, rpm, accel_100ms_);
  }
  return std::nullopt;
}

const NidecWasherDriver::Writes::Entry* NidecWasherDriver::front_to_send() {
  while (!queue_.empty()) {
    Writes::Entry& e = queue_.front();
    Queued& q = e.job;
    if (!q.request && q.job == Job::run) {
      // At the setpoint in force when the run reaches the line, so that a setpoint stored or
      // confirmed after the run command was written still counts.
      const auto rpm = static_cast<std::uint16_t>(std::clamp(common_.setpoint_rpm, 0, 0xFFFF));
      q.request = run_request(q.command, q.motion, rpm);
    } else if (!q.request && q.job == Job::setpoint) {
      if (!is_run(common_.command)) {
        // The run it was for is no longer in force (a stop or a fault came first): stored, as
        // when written while stopped.
        common_.setpoint_rpm = q.rpm;
        queue_.settle_front(WriteResult::ok);
        continue;
      }
      // The motion in force again at the new speed: each of those frames carries its target.
      q.request = run_request(common_.command, motion_in_force_, q.rpm);
    }
    if (q.request) return &e;
    // judge() keeps every run the frames cannot carry out; should one get here all the same, it
    // is refused rather than sent as something else.
    queue_.settle_front(WriteResult::refused);
  }
  return nullptr;
}

void NidecWasherDriver::complete_front(const Reply& r) {
  if (queue_.empty()) return;
  const Writes::Entry e = queue_.take_front();
  const Queued& q = e.job;
  const auto finish = [&](WriteResult result) { queue_.settle(e, result); };
  switch (q.job) {
    case Job::run:
      // Section 8: a faulted inverter does not start, and its ACK carries the Error bits
      // (apply_error() has already taken any run out of force).
      if (r.error() != 0) return finish(WriteResult::refused);
      motion_in_force_ = q.motion;
      set_command(q.command);
      return finish(WriteResult::ok);
    case Job::setpoint:
      // Not taken: the old setpoint stays in force (and the fault stopped the motor).
      if (r.error() != 0) return finish(WriteResult::refused);
      common_.setpoint_rpm = q.rpm;
      return finish(WriteResult::ok);
    case Job::stop:
      // A stop is in force whatever the Error byte says: a fault stops the motor too.
      set_command(q.command);
      return finish(WriteResult::ok);
    case Job::reset_fault:
      return finish(r.error() == 0 ? WriteResult::ok : WriteResult::refused);
    case Job::action:
      return finish(WriteResult::ok);
  }
}

// Told of every write as it settles, after it left the queue.
void NidecWasherDriver::settled(const Queued& q, WriteResult result) {
  if (q.job == Job::action) {
    const ActionStatus s =
        result == WriteResult::ok ? ActionStatus::done : ActionStatus::no_response;
    values_[pt::action_status] = std::int64_t{static_cast<std::int64_t>(s)};
  }
}

}  // namespace drivegate::nidec
