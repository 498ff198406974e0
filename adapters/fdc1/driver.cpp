// The stream: status frames into points and the common state; and what the line carries: the
// speed frame of the order under way (slave mode) and the programming frame.
#include "driver.h"

#include <algorithm>

#include "faults.h"

namespace drivegate::fdc1 {

Fdc1Driver::Fdc1Driver(const Settings& settings, bool programming)
    : DriverBase(make_points(programming)), settings_(settings), programming_(programming) {
  publish_program();
}

DriverTraits Fdc1Driver::traits() const {
  DriverTraits t;
  t.comm_timeout = settings_.stale;
  // Outlast both of the driver's own deadlines, so that it is the driver that says no_response.
  t.write_timeout =
      std::max<Millis>(settings_.confirm, kEchoTimeout * kEchoAttempts) + Millis(1000);
  t.inter_frame_gap = Millis(0);  // HARDWARE: separate RxD / TxD, the stream never blocks us
  return t;
}

// ---- the stream ----------------------------------------------------------------------------

RxVerdict Fdc1Driver::on_receive(ByteView rx, TimePoint now) {
  const auto d = decode_device(rx);
  if (const auto v = unless_frame(d)) return *v;
  expire(now);
  if (const auto* echo = std::get_if<Echo>(&d.frame)) return on_echo(*echo, d.consumed);
  on_status(std::get<Status>(d.frame), now);
  return {RxKind::frame, d.consumed};
}

void Fdc1Driver::on_status(const Status& s, TimePoint now) {
  if (!common_.ready) {
    common_.ready = true;
    adopt(s);
    // Start-up (and after comm_lost): tell the controller at once what the gateway holds, or the
    // write under way, rather than leave it on whatever an earlier session sent it.
    if (settings_.slave_mode) send_soon(now);
    publish_program();  // a commit may go now
  }
  last_status_ = s;
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
  confirm(s, now);
  publish_common();
}

// The first status since the driver began, before anything was written (the gateway restarted,
// or this device was changed by a reload): in slave mode a compressor found turning is kept
// turning at the speed it reports (the only speed the stream gives), rather than stopped by the
// start-up frame, and shown so (README, "Choices"). After a comm_lost the gateway's own order
// stands instead: that is what it last told the controller.
void Fdc1Driver::adopt(const Status& s) {
  if (!adopting_) return;
  adopting_ = false;
  if (!settings_.slave_mode || !s.motor_on || write_ || is_run(in_force_.command)) return;
  in_force_ = {Command::run_forward, std::clamp<std::int32_t>(s.rpm, kMinRpm, kMaxRpm)};
}

void Fdc1Driver::publish_common() {
  common_.command = in_force_.command;
  common_.setpoint_rpm = in_force_.setpoint;
  const bool motor_on = last_status_ && last_status_->motor_on;
  // "The motor turns or is commanded to": a run in force during an alarm still counts, since the
  // controller retries by itself (OUTPUT, the ranges before "end of retries").
  common_.running = motor_on || is_run(in_force_.command);
}

void Fdc1Driver::on_comm_lost(TimePoint now) {
  common_.ready = false;  // the start-up (the order in force, at once) runs again
  last_status_.reset();
  send_now_ = false;
  next_refresh_ = TimePoint::max();
  if (write_) fail_write(WriteResult::no_response, now);
  if (prog_state_ != Programming::idle) {
    finish_program(WriteResult::no_response, ProgStatus::no_response, "communication lost");
  }
  publish_common();
  publish_program();
}

// ---- what to send --------------------------------------------------------------------------

void Fdc1Driver::send_soon(TimePoint now) {
  send_now_ = true;
  due_at_ = now;
}

std::optional<Exchange> Fdc1Driver::next_exchange(TimePoint now) {
  expire(now);
  if (slave_ready() && (send_now_ || now >= next_refresh_)) {
    // INPUT, Programming speed, SLAVE MODE: "the minimum speed will become the actual speed";
    // "to stop the motor, a minimum speed equal to 0". The maximum is irrelevant in slave mode:
    // min = max = setpoint to run, and 0 / 3500 (an in-range maximum) to stop.
    const Order order = on_line();
    const auto rpm = static_cast<std::uint16_t>(is_run(order.command) ? order.setpoint : 0);
    Exchange ex;
    ex.frame = encode_speed(is_run(order.command) ? Speed{rpm, rpm} : Speed{0, kMaxRpm});
    ex.reply = ReplyMode::none;  // INPUT, Programming speed: never acknowledged
    send_now_ = false;
    if (write_) write_->sent = true;
    next_refresh_ = now + settings_.refresh;
    values_[pt::sent_speed_rpm] = std::int64_t{rpm};
    return ex;
  }
  if (prog_state_ == Programming::queued && common_.ready) {
    Exchange ex;
    ex.frame = encode_program(prog_sent_);
    ex.reply = ReplyMode::expected;
    ex.timeout = kEchoTimeout;
    ex.attempts = kEchoAttempts;
    prog_state_ = Programming::awaiting_echo;
    return ex;
  }
  return std::nullopt;
}

TimePoint Fdc1Driver::wake_at() const {
  TimePoint wake = slave_ready() ? (send_now_ ? due_at_ : next_refresh_) : TimePoint::max();
  if (prog_state_ == Programming::queued) wake = std::min(wake, due_at_);
  if (write_) wake = std::min(wake, write_->deadline);
  return wake;
}

void Fdc1Driver::on_no_reply(TimePoint) {
  if (prog_state_ == Programming::awaiting_echo) {
    finish_program(WriteResult::no_response, ProgStatus::no_response,
                   "the controller did not echo the programming frame");
  }
}

}  // namespace drivegate::fdc1
