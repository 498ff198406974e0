#include "driver.h"

#include <algorithm>
#include <cstdlib>

#include "alarms.h"
#include "points.h"

namespace drivegate::fdc1 {

Fdc1Driver::Fdc1Driver(const Settings& settings, bool programming)
    : settings_(settings), programming_(programming), points_(make_points(programming)) {
  values_.resize(points_.size());
  if (programming_) values_[pt::prog_status] = static_cast<std::int64_t>(ProgStatus::idle);
}

DriverTraits Fdc1Driver::traits() const {
  DriverTraits t;
  t.comm_timeout = settings_.stale;
  // Outlast both of the driver's own deadlines, so that it is the driver that says no_response.
  t.write_timeout =
      std::max<Millis>(settings_.confirm, kEchoTimeout * kEchoAttempts) + Millis(1000);
  t.inter_frame_gap = Millis(0);  // full-duplex UART: the stream never blocks the master
  return t;
}

// ---- the stream ----------------------------------------------------------------------------

RxVerdict Fdc1Driver::on_receive(ByteView rx, TimePoint now) {
  const auto d = decode_device(rx);
  switch (d.status) {
    case DecodeStatus::incomplete:
      return {RxKind::incomplete, 0};
    case DecodeStatus::bad:
      return damaged(d);
    case DecodeStatus::frame:
      break;
  }
  expire(now);
  if (const auto* echo = std::get_if<Echo>(&d.frame)) {
    const RxVerdict v = on_echo(*echo);
    return {v.kind, d.consumed};
  }
  apply(std::get<Status>(d.frame), now);
  return {RxKind::frame, d.consumed};
}

void Fdc1Driver::apply(const Status& s, TimePoint now) {
  if (!common_.ready) {
    common_.ready = true;
    // Start-up: assert the command in force at once (slave mode), then refresh it. A write that
    // came before the first frame keeps its command priority.
    if (settings_.slave_mode) {
      send_now_ = true;
      due_at_ = now;
      send_priority_ = speed_write_ ? Priority::command : Priority::poll;
    }
  }
  motor_on_ = s.motor_on;
  const Alarm alarm = classify_alarm(s.motor_on ? 0 : s.alarm);
  values_[pt::motor_on] = std::int64_t{s.motor_on ? 1 : 0};
  values_[pt::current_a] = s.current_a();
  values_[pt::restart_s] = s.restart_s();
  values_[pt::alarm_code] = std::int64_t{s.motor_on ? 0 : s.alarm};
  values_[pt::alarm_latched] = std::int64_t{alarm.latched ? 1 : 0};

  common_.speed_rpm = s.motor_on ? s.rpm : 0;
  common_.native_fault = s.motor_on ? 0 : s.alarm;
  common_.faults = FaultSet{};
  if (alarm.fault != Fault::none) common_.faults.set(alarm.fault);
  common_.running = motor_on_ || common_.command == Command::run_forward;
  confirm(s);
}

void Fdc1Driver::confirm(const Status& s) {
  if (!speed_write_) return;
  const bool alarmed = !s.motor_on && s.alarm != 0;
  bool ok = false;
  switch (speed_write_->expect) {
    case Expect::motor_off:
      ok = !s.motor_on;
      break;
    case Expect::motor_on:
      ok = s.motor_on;
      break;
    case Expect::at_setpoint:
      ok = s.motor_on && std::abs(s.rpm - setpoint_) <= settings_.tolerance_rpm;
      break;
  }
  if (ok) {
    finish_speed_write(WriteResult::ok);
  } else if (alarmed && speed_write_->expect != Expect::motor_off) {
    // The controller is in alarm: the run was refused, so it must not stay in force (the
    // controller would start by itself once the alarm clears, after the PLC was told no).
    finish_speed_write(WriteResult::refused);
    common_.command = Command::stop;
    common_.running = false;
    send_now_ = true;
  }
}

void Fdc1Driver::expire(TimePoint now) {
  if (speed_write_ && now >= speed_write_->deadline) give_up_speed_write();
}

// The pending writes get 0x0B. If no frame ever carried them (the controller was not heard since
// they were asked for), they must not stay in force: the start-up after the controller appears
// would otherwise carry out what the PLC was told failed, starting the compressor hours later.
// A frame that did go out may have been acted on, so then the command stays in force (and is
// sent again when the stream returns, as for any command in force).
void Fdc1Driver::give_up_speed_write() {
  if (!speed_write_) return;
  const bool sent = speed_write_->sent;
  const InForce before = speed_write_->before;
  finish_speed_write(WriteResult::no_response);
  if (sent) return;
  common_.command = before.command;
  setpoint_ = before.setpoint;
  common_.setpoint_rpm = before.setpoint;
  common_.running = motor_on_ || common_.command == Command::run_forward;
}

void Fdc1Driver::finish_speed_write(WriteResult r) {
  if (!speed_write_) return;
  for (const Ticket t : speed_write_->tickets) complete(t, r);
  speed_write_.reset();
}

void Fdc1Driver::on_comm_lost(TimePoint) {
  common_.ready = false;  // the start-up (re-assert the command in force) runs again
  send_now_ = false;
  next_refresh_ = TimePoint::max();
  give_up_speed_write();
  if (prog_state_ != Programming::idle) {
    finish_program(WriteResult::no_response, ProgStatus::no_response, "communication lost");
  }
}

// ---- what to send --------------------------------------------------------------------------

Speed Fdc1Driver::wanted_speed() const {
  // INPUT, Programming speed, SLAVE MODE: "the minimum speed will become the actual speed";
  // "to stop the motor, a minimum speed equal to 0". The maximum is irrelevant in slave mode:
  // drivegate sends min = max = setpoint to run, and 0 / 3500 (an in-range maximum) to stop.
  if (common_.command == Command::run_forward) {
    const auto rpm = static_cast<std::uint16_t>(setpoint_);
    return {rpm, rpm};
  }
  return {0, kMaxRpm};
}

std::optional<Exchange> Fdc1Driver::next_exchange(TimePoint now) {
  expire(now);
  if (slave_ready() && (send_now_ || now >= next_refresh_)) {
    Exchange ex;
    const Speed speed = wanted_speed();
    ex.frame = encode_speed(speed);
    ex.reply = ReplyMode::none;  // INPUT, Programming speed: never acknowledged
    ex.priority = send_now_ ? send_priority_ : Priority::poll;
    send_now_ = false;
    if (speed_write_) speed_write_->sent = true;
    next_refresh_ = now + settings_.refresh;
    values_[pt::sent_speed_rpm] = std::int64_t{speed.min_rpm};
    return ex;
  }
  if (prog_state_ == Programming::queued && common_.ready) {
    Exchange ex;
    ex.frame = encode_program(prog_sent_);
    ex.reply = ReplyMode::expected;
    ex.timeout = kEchoTimeout;
    ex.attempts = kEchoAttempts;
    ex.priority = Priority::command;
    prog_state_ = Programming::awaiting_echo;
    return ex;
  }
  return std::nullopt;
}

TimePoint Fdc1Driver::wake_at() const {
  TimePoint wake = slave_ready() ? (send_now_ ? due_at_ : next_refresh_) : TimePoint::max();
  if (prog_state_ == Programming::queued) wake = std::min(wake, due_at_);
  if (speed_write_) wake = std::min(wake, speed_write_->deadline);
  return wake;
}

void Fdc1Driver::on_no_reply(TimePoint) {
  if (prog_state_ == Programming::awaiting_echo) {
    finish_program(WriteResult::no_response, ProgStatus::no_response,
                   "the controller did not echo the programming frame");
  }
}

// ---- writes --------------------------------------------------------------------------------

void Fdc1Driver::start_speed_write(Ticket t, Expect e, InForce before, TimePoint now) {
  std::vector<Ticket> tickets;
  if (speed_write_) {
    before = speed_write_->before;  // what was in force before any of the unsettled writes
    // Every frame carries both the command and the setpoint, so a pending write that asked for
    // the same direction (run / run, stop / stop) is carried out by the new frame too: it waits
    // with the new write, on the stricter test. One asking the opposite is superseded.
    const bool old_runs = speed_write_->expect != Expect::motor_off;
    const bool new_runs = e != Expect::motor_off;
    if (old_runs == new_runs) {
      tickets = std::move(speed_write_->tickets);
      if (speed_write_->expect == Expect::at_setpoint) e = Expect::at_setpoint;
      speed_write_.reset();
    } else {
      finish_speed_write(WriteResult::no_response);
    }
  }
  tickets.push_back(t);
  speed_write_ = SpeedWrite{std::move(tickets), e, now + settings_.confirm, before};
  send_now_ = true;
  due_at_ = now;
  send_priority_ = Priority::command;
}

WriteStatus Fdc1Driver::command(Command c, Ticket t, TimePoint now) {
  switch (c) {
    case Command::run_reverse:
      return WriteStatus::invalid_value;  // a compressor: one direction
    case Command::reset_fault:
      return WriteStatus::invalid_value;  // no reset in the protocol
    default:
      break;
  }
  if (!settings_.slave_mode) return WriteStatus::invalid_value;  // speed set by IN1/IN2 then
  // Before the controller is first heard the write waits: the start-up sends the command in
  // force as soon as the stream begins (give_up_speed_write() if it never does).
  const InForce before = in_force();
  if (c == Command::run_forward) {
    if (setpoint_ == 0) return WriteStatus::refused;  // no speed to run at yet
    common_.command = c;
    common_.running = true;
    start_speed_write(t, Expect::motor_on, before, now);
    return WriteStatus::pending;
  }
  // stop, and quick_stop: the protocol has no faster stop than speed 0.
  common_.command = c;
  common_.running = motor_on_;
  start_speed_write(t, Expect::motor_off, before, now);
  return WriteStatus::pending;
}

WriteStatus Fdc1Driver::setpoint(std::int32_t rpm, Ticket t, TimePoint now) {
  if (!settings_.slave_mode) return WriteStatus::invalid_value;
  if (rpm < kMinRpm || rpm > kMaxRpm) return WriteStatus::invalid_value;
  if (common_.command != Command::run_forward) {
    setpoint_ = rpm;
    common_.setpoint_rpm = rpm;
    return WriteStatus::done;  // used by the next run_forward
  }
  const InForce before = in_force();
  setpoint_ = rpm;
  common_.setpoint_rpm = rpm;
  start_speed_write(t, Expect::at_setpoint, before, now);
  return WriteStatus::pending;
}

void Fdc1Driver::complete(Ticket t, WriteResult r) {
  completions_.push_back({t, r});
}

void Fdc1Driver::take_completions(std::vector<Completion>& out) {
  out.insert(out.end(), completions_.begin(), completions_.end());
  completions_.clear();
}

std::unique_ptr<Driver> make_driver(const DeviceEnv& env, std::string& error) {
  const Settings s = read_settings(env.options);
  if (s.refresh >= std::chrono::seconds(60)) {
    error = "refresh_s must stay under the controller's 60 s watchdog";
    return nullptr;
  }
  return std::make_unique<Fdc1Driver>(s, env.maintenance || s.allow_nv_programming);
}

}  // namespace drivegate::fdc1
