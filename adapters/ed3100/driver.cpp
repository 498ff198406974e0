#include "driver.h"

#include <algorithm>
#include <cmath>

#include "faults.h"
#include "points.h"

namespace drivegate::ed3100 {
namespace {

// A broadcast drive never answers (document, "00H: ... slave radio machine not respond"): no
// good frame ever arrives, so comm_lost must not be judged on it.
constexpr Millis kBroadcastCommTimeout = std::chrono::hours(24 * 365);

}  // namespace

Ed3100Driver::Ed3100Driver(std::uint8_t address, Settings settings, Millis poll_interval)
    : settings_(std::move(settings)),
      address_(address),
      poll_interval_(poll_interval),
      param_known_(settings_.parameters.size(), false) {
  points_ = make_points(settings_);
  values_.resize(points_.size());
  values_[pt::frequency_setpoint] = 0.0;
}

// The longest one exchange of this drive takes: every attempt's wait and the engine's guard time
// after it, gap and time on the wire.
Millis Ed3100Driver::turn() const {
  return settings_.attempts *
         (unanswered_attempt(settings_.timeout) + settings_.frame_gap + kWireAllowance);
}

// A write waits for the line at most one exchange of this drive in flight (a poll) and one turn
// of another device.
Millis Ed3100Driver::send_limit() const {
  return turn() + kOtherTurnAllowance;
}

DriverTraits Ed3100Driver::traits() const {
  DriverTraits t;
  t.comm_timeout = broadcast() ? kBroadcastCommTimeout : settings_.comm_timeout;
  // Every write settles (confirmed, refused, unanswered, or failed unsent) within send_limit()
  // and one turn of its own, and a request holds at most two that need the line (a setpoint
  // while running, then a command): the gateway's deadline is never the one that answers.
  t.write_timeout = std::max(kWriteTimeoutFloor, 2 * (send_limit() + turn()) + kDeadlineMargin);
  t.inter_frame_gap = settings_.frame_gap;
  return t;
}

Ed3100Driver::Job Ed3100Driver::read_job(Op op, std::size_t slot, std::uint16_t reg) {
  Job j;
  j.op = op;
  j.slot = slot;
  j.reg = reg;
  return j;
}

ReplyShape Ed3100Driver::shape(const Job& j) const {
  switch (j.op) {
    case Op::read_fault:
      return {kFnRead, j.reg, kFaultWords};
    case Op::read_monitor:
      return {kFnRead, j.reg, kMonitorWords};
    case Op::read_param:
      return {kFnRead, j.reg, 1};
    case Op::write:
      break;
  }
  return {j.words.size() > 1 ? kFnWriteMultiple : kFnWriteSingle, j.reg,
          static_cast<std::uint16_t>(j.words.size())};
}

Exchange Ed3100Driver::exchange(const Job& j) const {
  Exchange ex;
  switch (j.op) {
    case Op::read_fault:
    case Op::read_monitor:
      // Sent as the document prints them: 00 00 where the quantity belongs.
      ex.frame = encode_read(address_, j.reg, kRetainedCount);
      break;
    case Op::read_param:
      ex.frame = encode_read(address_, j.reg, 1);
      break;
    case Op::write:
      ex.frame = j.words.size() > 1 ? encode_write_multiple(address_, j.reg, j.words)
                                    : encode_write_single(address_, j.reg, j.words.at(0));
      break;
  }
  ex.reply = broadcast() ? ReplyMode::none : ReplyMode::expected;
  ex.timeout = settings_.timeout;
  ex.attempts = broadcast() ? 1 : settings_.attempts;
  return ex;
}

// At start-up and after comm_lost: every parameter not read yet, then the fault/state word and
// the monitors, every poll_interval.
void Ed3100Driver::start_cycle(TimePoint now) {
  for (std::size_t p = 0; p < settings_.parameters.size(); ++p) {
    if (!param_known_[p]) reads_.push_back(read_job(Op::read_param, p, settings_.parameters[p]));
  }
  reads_.push_back(read_job(Op::read_fault, 0, kRegFault));
  for (std::size_t m = 0; m < settings_.monitors.size(); ++m) {
    reads_.push_back(read_job(Op::read_monitor, m, settings_.monitors[m].reg));
  }
  next_cycle_ = now + poll_interval_;
}

std::optional<Exchange> Ed3100Driver::next_exchange(TimePoint now) {
  last_now_ = now;
  writes_.expire_after(now);
  // The engine asks only once the exchange before ended; one it abandoned without a word still
  // owes its write an answer.
  fail_inflight();
  if (std::optional<Job> w = next_write()) {
    Exchange ex = exchange(*w);
    if (broadcast()) {
      // Nothing will ever confirm a broadcast: it counts as taken once handed to the bus.
      put_in_force(w->write->job);
      writes_.settle(*w->write, WriteResult::ok);
    } else {
      inflight_ = std::move(w);
    }
    return ex;
  }
  if (broadcast()) return std::nullopt;
  if (reads_.empty() && now >= next_cycle_) start_cycle(now);
  if (reads_.empty()) return std::nullopt;
  inflight_ = std::move(reads_.front());
  reads_.pop_front();
  return exchange(*inflight_);
}

TimePoint Ed3100Driver::wake_at() const {
  if (!writes_.empty() || !reads_.empty()) return last_now_;
  if (broadcast()) return TimePoint::max();
  return next_cycle_;
}

RxVerdict Ed3100Driver::on_receive(ByteView rx, TimePoint now) {
  last_now_ = now;
  if (rx.empty()) return {};
  if (!inflight_) return {RxKind::noise, rx.size()};
  const Decoded<Reply> d = decode_reply(rx, shape(*inflight_));
  switch (d.status) {
    case DecodeStatus::incomplete:
      return {};
    case DecodeStatus::bad:
      // RTU has no start marker: a CRC failure whose first byte is not this drive's address is
      // a window on noise rather than its damaged reply, so skip one byte and look again.
      if (d.error == FrameError::bad_checksum && rx[0] != address_) return {RxKind::noise, 1};
      return damaged(d);
    case DecodeStatus::frame:
      break;
  }
  const Reply& r = d.frame;
  // A good frame for another address, or a document-form reply or echo naming another register,
  // is not the reply awaited.
  const bool echoes_reg = r.kind == ReplyKind::read_document || r.kind == ReplyKind::write_echo;
  if (r.address != address_ || (echoes_reg && r.reg != inflight_->reg)) {
    return {RxKind::foreign, d.consumed};
  }
  const Job job = std::move(*inflight_);
  inflight_.reset();
  on_reply(job, r);
  // A write's echo or an exception says nothing of the drive's state: data_age_ms runs on.
  const bool state = job.op != Op::write && r.kind != ReplyKind::exception;
  return {state ? RxKind::reply : RxKind::ack, d.consumed};
}

void Ed3100Driver::on_reply(const Job& j, const Reply& r) {
  if (j.op == Op::write) {
    confirm(j, r);
  } else if (r.kind == ReplyKind::exception) {
    // A read refused: a parameter the drive does not have stays unknown, and is not asked for
    // again until the next reconnect (README, "Choices", 7).
    if (j.op == Op::read_param) param_known_[j.slot] = true;
  } else {
    switch (j.op) {
      case Op::read_fault:
        fault_known_ = true;
        apply_fault(r.words);
        break;
      case Op::read_monitor:
        apply_monitor(j.slot, r.words);
        break;
      case Op::read_param:
        values_[pt::parameter(settings_, j.slot)] = static_cast<std::int64_t>(r.words.at(0));
        param_known_[j.slot] = true;
        break;
      case Op::write:
        break;
    }
  }
  update_ready();
}

void Ed3100Driver::on_no_reply(TimePoint now) {
  last_now_ = now;
  fail_inflight();
}

void Ed3100Driver::on_comm_lost(TimePoint now) {
  on_no_reply(now);  // the exchange on the line, if any, is over unanswered
  // Nothing waiting is sent once the drive answers again: the PLC was told these failed.
  writes_.settle_all(WriteResult::no_response);
  reads_.clear();
  std::fill(param_known_.begin(), param_known_.end(), false);
  fault_known_ = false;
  common_.ready = false;
  next_cycle_ = now;
}

// --- replies into points and the common state ---

void Ed3100Driver::apply_fault(const std::vector<std::uint16_t>& w) {
  fault_word_ = w.at(0);
  state_word_ = w.at(1);
  auto flag = [&](unsigned b) { return static_cast<std::int64_t>(bit(state_word_, b)); };
  values_[pt::drive_fault_code] = static_cast<std::int64_t>(fault_word_);
  values_[pt::state_word] = static_cast<std::int64_t>(state_word_);
  values_[pt::running] = flag(kStRunning);
  values_[pt::direction] = flag(kStRunReverse);
  values_[pt::commanded_direction] = flag(kStCmdReverse);
  values_[pt::accelerating] = flag(kStAccelerating);
  values_[pt::decelerating] = flag(kStDecelerating);
  common_.running = bit(state_word_, kStRunning);
  common_.faults = faults_of(fault_word_);
  common_.native_fault = native_fault_of(fault_word_);
  // A trip stops the output: the run in force is over, and the drive needs a new run command
  // once reset (README, "Choices", 11).
  if (tripped(fault_word_) && !common_.running && is_run(common_.command)) {
    common_.command = Command::stop;
  }
  update_speed();
  adopt();
}

// A drive found running, before anything was written to it, runs on as it is: its commanded
// direction is the command in force, its output frequency the reference (and the setpoint), so
// that the registers never say stop over a turning motor and the next write starts from what
// the drive does. Once the status and the speed are known, or at the first write, adoption ends.
void Ed3100Driver::adopt() {
  if (!adopting_ || !fault_known_ || !speed_hz_) return;
  adopting_ = false;
  if (!common_.running || tripped(fault_word_)) return;
  common_.command = bit(state_word_, kStCmdReverse) ? Command::run_reverse : Command::run_forward;
  const long long centi = std::llround(*speed_hz_ * 100.0);
  set_reference(static_cast<std::uint16_t>(std::clamp<long long>(centi, 0, 0xFFFF)),
                rpm_from_hz(*speed_hz_));
}

void Ed3100Driver::apply_monitor(std::size_t slot, const std::vector<std::uint16_t>& w) {
  const std::uint16_t raw = w.at(0);
  const std::uint16_t format = w.at(1);
  // Values are taken unsigned: the document names no sign.
  const double value = raw * format_scale(format);
  values_[pt::monitor_value(slot)] = value;
  values_[pt::monitor_raw(slot)] = static_cast<std::int64_t>(raw);
  values_[pt::monitor_format(slot)] = static_cast<std::int64_t>(format);
  if (slot == settings_.speed_monitor) {
    speed_hz_ = value;
    speed_stopped_ = bit(format, kFmtStopped);
    update_speed();
    adopt();
  }
}

void Ed3100Driver::update_speed() {
  if (!speed_hz_) return;
  // Stopped, the monitor shows the reference rather than the output (document example:
  // 42.28 Hz with the stopped bit): the motor does not turn.
  const bool turning = !speed_stopped_ && (!fault_known_ || bit(state_word_, kStRunning));
  std::int32_t rpm = turning ? rpm_from_hz(*speed_hz_) : 0;
  if (bit(state_word_, kStRunReverse)) rpm = -rpm;
  common_.speed_rpm = rpm;
}

void Ed3100Driver::update_ready() {
  common_.ready = fault_known_ &&
                  std::all_of(param_known_.begin(), param_known_.end(), [](bool b) { return b; });
}

std::int32_t Ed3100Driver::rpm_from_hz(double hz) const {
  // Synchronous speed: rpm = Hz x 120 / poles (option `poles`).
  return static_cast<std::int32_t>(std::lround(hz * 120.0 / settings_.poles));
}

std::optional<std::uint16_t> Ed3100Driver::centi_hz_from_rpm(std::int32_t rpm) const {
  if (rpm < 0) return std::nullopt;  // direction is the command's business
  const long long centi = std::llround(rpm * settings_.poles * 100.0 / 120.0);
  if (centi > 0xFFFF) return std::nullopt;  // 0x2001 is one 16-bit word in 0.01 Hz
  return static_cast<std::uint16_t>(centi);
}

}  // namespace drivegate::ed3100
