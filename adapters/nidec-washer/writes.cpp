// WasherDriver: Modbus writes translated into queued frames.
#include <cmath>

#include "driver.h"
#include "faults.h"

namespace drivegate::nidec {
namespace {

bool is_run(Command c) {
  return c == Command::run_forward || c == Command::run_reverse;
}

// The integer a write carries, however the gateway scaled it.
std::optional<std::int64_t> whole(const Value& v, double factor = 1.0) {
  if (std::holds_alternative<std::monostate>(v) || std::holds_alternative<std::string>(v)) {
    return std::nullopt;
  }
  return std::llround(as_double(v) * factor);
}

}  // namespace

std::optional<Request> WasherDriver::run_request(Command c, Motion m) const {
  const bool reverse = c == Command::run_reverse;
  switch (m) {
    case Motion::rotation:
      return make_run(reverse ? Mode::ccw : Mode::cw, setpoint_, accel_100ms_);  // 5.3 / 5.4
    case Motion::spin:
      if (reverse) return std::nullopt;  // 5.6 has no direction
      return make_run(Mode::spin, setpoint_, accel_100ms_);
    case Motion::agitation:
      if (reverse) return std::nullopt;  // 5.5 alternates CW and CCW by itself
      return make_agitation(setpoint_, agitation_);
    case Motion::free_shaft_spin:
      if (reverse) return std::nullopt;  // 5.14 has no direction
      return make_run(Mode::free_shaft_spin, setpoint_, accel_100ms_);
  }
  return std::nullopt;
}

WriteStatus WasherDriver::enqueue(Queued q) {
  queue_.push_back(std::move(q));
  return WriteStatus::pending;
}

WriteStatus WasherDriver::command(Command c, Ticket t, TimePoint now) {
  const TimePoint deadline = now + config_.confirm_timeout;
  switch (c) {
    case Command::stop:  // 5.7: closed-loop stop
      return enqueue({make_bare(Mode::stop), Job::stop, t, deadline, Command::stop});
    case Command::quick_stop:  // 5.8: brake, open loop, as fast as possible
      return enqueue({make_bare(Mode::brake), Job::stop, t, deadline, Command::quick_stop});
    case Command::reset_fault:  // no reset frame: ask (5.2) whether the fault has cleared
      return enqueue({make_bare(Mode::request), Job::reset_fault, t, deadline, c});
    case Command::run_forward:
    case Command::run_reverse: {
      const std::optional<Request> r = run_request(c, motion_);
      if (!r) return WriteStatus::invalid_value;
      if (common_.native_fault != 0 || forced_brake_) return WriteStatus::refused;
      return enqueue({*r, Job::run, t, deadline, c, motion_});
    }
  }
  return WriteStatus::invalid_value;
}

WriteStatus WasherDriver::setpoint(std::int32_t rpm, Ticket t, TimePoint now) {
  if (rpm < 0 || rpm > 0xFFFF) return WriteStatus::invalid_value;  // 5.3: 16-bit speed
  setpoint_ = static_cast<std::uint16_t>(rpm);
  common_.setpoint_rpm = rpm;
  if (!is_run(common_.command)) return WriteStatus::done;  // used by the next run_*
  const std::optional<Request> r = run_request(common_.command, motion_in_force_);
  if (!r) return WriteStatus::done;
  return enqueue(
      {*r, Job::run, t, now + config_.confirm_timeout, common_.command, motion_in_force_});
}

WriteStatus WasherDriver::write(std::size_t point, const Value& v, Ticket t, TimePoint now) {
  const bool time_point =
      point == pt::accel_time || (point >= pt::agitation_accel && point <= pt::agitation_ccw_off);
  const std::optional<std::int64_t> n = whole(v, time_point ? 10.0 : 1.0);  // 100 ms units
  if (!n || *n < 0) return WriteStatus::invalid_value;
  if (point == pt::motion) {
    if (*n > static_cast<std::int64_t>(Motion::free_shaft_spin)) return WriteStatus::invalid_value;
    motion_ = static_cast<Motion>(*n);
    values_[pt::motion] = *n;
    return WriteStatus::done;
  }
  if (point == pt::accel_time) {
    if (*n > 0xFFFF) return WriteStatus::invalid_value;  // 5.3: 16 bits
    accel_100ms_ = static_cast<std::uint16_t>(*n);
    values_[point] = static_cast<double>(*n) / 10.0;
    return WriteStatus::done;
  }
  if (time_point) {
    if (*n > 0xFF) return WriteStatus::invalid_value;  // 5.5: one byte each
    const auto b = static_cast<std::uint8_t>(*n);
    std::uint8_t* fields[] = {&agitation_.accel,  &agitation_.decel,  &agitation_.cw_on,
                              &agitation_.cw_off, &agitation_.ccw_on, &agitation_.ccw_off};
    *fields[point - pt::agitation_accel] = b;
    values_[point] = static_cast<double>(b) / 10.0;
    return WriteStatus::done;
  }
  if (point == pt::action) return write_action(*n, t, now);
  return WriteStatus::invalid_value;
}

WriteStatus WasherDriver::write_action(std::int64_t n, Ticket t, TimePoint now) {
  if (n > kActionMax) return WriteStatus::invalid_value;
  const auto action = static_cast<Action>(n);
  values_[pt::action] = n;
  std::optional<Request> r;
  switch (action) {
    case Action::none:
      return WriteStatus::done;
    case Action::voltage_detection:
      r = make_bare(Mode::voltage_detection);
      break;
    case Action::weight_detection:
      r = make_bare(Mode::weight_detection);
      break;
    case Action::fabric_detection:
      r = make_bare(Mode::fabric_detection);
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
      r = make_ping(config_.platform, config_.empty_raw_weight);
      break;
  }
  values_[pt::action_status] = static_cast<std::int64_t>(ActionStatus::pending);
  return enqueue({*r, Job::action, t, now + config_.confirm_timeout});
}

}  // namespace drivegate::nidec
