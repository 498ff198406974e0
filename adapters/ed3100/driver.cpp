#include "driver.h"

#include <algorithm>
#include <cmath>

#include "points.h"

namespace drivegate::ed3100 {
namespace {

// A broadcast drive never answers (document, "00H: ... slave radio machine not respond"): no
// good frame ever arrives, so comm_lost must not be judged on it.
constexpr Millis kBroadcastCommTimeout = std::chrono::hours(24 * 365);
// The gateway's own deadline for a pending write, at least the 3 s API default and never
// shorter than a full turn of retries behind a poll.
constexpr Millis kWriteTimeoutFloor{3000};

bool is_run(Command c) {
  return c == Command::run_forward || c == Command::run_reverse;
}

}  // namespace

Ed3100Driver::Ed3100Driver(Config config, Millis poll_interval)
    : config_(std::move(config)),
      poll_interval_(poll_interval),
      points_(make_points(config_)),
      values_(points_.size()),
      param_known_(config_.parameters.size(), false) {
  values_[index(Fixed::frequency_setpoint)] = 0.0;
}

DriverTraits Ed3100Driver::traits() const {
  DriverTraits t;
  t.comm_timeout = broadcast() ? kBroadcastCommTimeout : config_.comm_timeout;
  t.write_timeout =
      std::max(kWriteTimeoutFloor, 3 * config_.attempts * (config_.timeout + config_.frame_gap));
  t.inter_frame_gap = config_.frame_gap;
  return t;
}

ReplyShape Ed3100Driver::shape(const Job& j) const {
  switch (j.op) {
    case Op::read_fault:
      return {kFnRead, j.reg, kFaultWords};
    case Op::read_monitor:
      return {kFnRead, j.reg, kMonitorWords};
    case Op::read_param:
      return {kFnRead, j.reg, 1};
    default:
      return {j.words.size() > 1 ? kFnWriteMultiple : kFnWriteSingle, j.reg,
              static_cast<std::uint16_t>(j.words.size())};
  }
}

Exchange Ed3100Driver::exchange(const Job& j) const {
  Exchange ex;
  switch (j.op) {
    case Op::read_fault:
    case Op::read_monitor:
      // Sent as the document prints them: 00 00 where the quantity belongs.
      ex.frame = encode_read(config_.address, j.reg, kRetainedCount);
      break;
    case Op::read_param:
      ex.frame = encode_read(config_.address, j.reg, 1);
      break;
    default:
      ex.frame = j.words.size() > 1 ? encode_write_multiple(config_.address, j.reg, j.words)
                                    : encode_write_single(config_.address, j.reg, j.words[0]);
      ex.priority = Priority::command;
      break;
  }
  ex.reply = broadcast() ? ReplyMode::none : ReplyMode::expected;
  ex.timeout = config_.timeout;
  ex.attempts = broadcast() ? 1 : config_.attempts;
  return ex;
}

void Ed3100Driver::start_cycle(TimePoint now) {
  for (std::size_t p = 0; p < config_.parameters.size(); ++p) {
    if (!param_known_[p]) reads_.push_back(Job::make(Op::read_param, p, config_.parameters[p]));
  }
  reads_.push_back(Job::make(Op::read_fault, 0, kRegFault));
  for (std::size_t m = 0; m < config_.monitors.size(); ++m) {
    reads_.push_back(Job::make(Op::read_monitor, m, config_.monitors[m].reg));
  }
  next_cycle_ = now + poll_interval_;
}

std::optional<Exchange> Ed3100Driver::next_exchange(TimePoint now) {
  last_now_ = now;
  inflight_.reset();
  if (!writes_.empty()) {
    Job j = std::move(writes_.front());
    writes_.pop_front();
    Exchange ex = exchange(j);
    if (broadcast()) {
      // Nothing will ever confirm a broadcast: it counts as done once handed to the bus.
      apply(j, Reply{config_.address, shape(j).function, ReplyKind::write_echo, j.reg, 0, {}, 0});
    } else {
      inflight_ = std::move(j);
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
      // A frame-shaped run of bytes from our drive with a bad CRC is resent; anything else is
      // skipped a byte at a time until a frame starts (RTU has no start marker).
      if (d.error == FrameError::bad_checksum && rx[0] == config_.address) {
        return {RxKind::bad_checksum, d.consumed};
      }
      return {RxKind::noise, 1};
    case DecodeStatus::frame:
      break;
  }
  const Reply& r = d.frame;
  const bool echoes_reg = r.kind == ReplyKind::read_document || r.kind == ReplyKind::write_echo;
  if (r.address != config_.address || (echoes_reg && r.reg != inflight_->reg)) {
    return {RxKind::foreign, d.consumed};
  }
  const Job job = std::move(*inflight_);
  inflight_.reset();
  apply(job, r);
  return {RxKind::reply, d.consumed};
}

void Ed3100Driver::apply(const Job& j, const Reply& r) {
  if (r.kind == ReplyKind::exception) {
    // A drive that refuses a write says so with an exception (Modbus application protocol 7).
    if (j.ticket) complete(j, WriteResult::refused);
    if (j.op == Op::read_param) param_known_[j.slot] = true;  // it has no such parameter
    update_ready();
    return;
  }
  switch (j.op) {
    case Op::read_fault:
      fault_known_ = true;
      apply_fault(r.words);
      break;
    case Op::read_monitor:
      apply_monitor(j.slot, r.words);
      break;
    case Op::read_param:
      values_[parameter_index(config_, j.slot)] = static_cast<std::int64_t>(r.words.at(0));
      param_known_[j.slot] = true;
      break;
    case Op::write_command:
      common_.command = j.command;
      if (is_run(j.command)) common_.running = true;
      complete(j, WriteResult::ok);
      break;
    case Op::write_param:
      values_[parameter_index(config_, j.slot)] = static_cast<std::int64_t>(j.words[0]);
      complete(j, WriteResult::ok);
      if (!broadcast())
        reads_.push_front(Job::make(Op::read_param, j.slot, j.reg));  // read it back
      break;
    case Op::write_frequency:
    case Op::write_reset:
      complete(j, WriteResult::ok);
      break;
  }
  update_ready();
}

void Ed3100Driver::complete(const Job& j, WriteResult r) {
  if (j.ticket) completions_.push_back({*j.ticket, r});
}

void Ed3100Driver::on_no_reply(TimePoint now) {
  last_now_ = now;
  if (inflight_) complete(*inflight_, WriteResult::no_response);
  inflight_.reset();
}

void Ed3100Driver::on_comm_lost(TimePoint now) {
  last_now_ = now;
  if (inflight_) complete(*inflight_, WriteResult::no_response);
  inflight_.reset();
  for (const Job& j : writes_) complete(j, WriteResult::no_response);
  writes_.clear();
  reads_.clear();
  std::fill(param_known_.begin(), param_known_.end(), false);
  fault_known_ = false;
  common_.ready = false;
  next_cycle_ = now;
}

std::int32_t Ed3100Driver::rpm_from_hz(double hz) const {
  // Synchronous speed: rpm = Hz x 120 / poles (issue 3, option `poles`).
  return static_cast<std::int32_t>(std::lround(hz * 120.0 / config_.poles));
}

std::optional<std::uint16_t> Ed3100Driver::centi_hz_from_rpm(std::int32_t rpm) const {
  if (rpm < 0) return std::nullopt;  // direction is the command's business
  const long long centi = std::llround(rpm * config_.poles * 100.0 / 120.0);
  if (centi > 0xFFFF) return std::nullopt;
  return static_cast<std::uint16_t>(centi);
}

WriteStatus Ed3100Driver::queue_write(Job j, Ticket t) {
  j.ticket = t;
  writes_.push_back(std::move(j));
  return WriteStatus::pending;
}

WriteStatus Ed3100Driver::command(Command c, Ticket t, TimePoint now) {
  last_now_ = now;
  Job j;
  j.reg = kRegCommand;
  j.command = c;
  j.op = Op::write_command;
  switch (c) {
    case Command::run_forward:
    case Command::run_reverse:
      if (fault_word_ != kNoFault) return WriteStatus::refused;  // a tripped drive cannot run
      // Command and reference in one 10 write, as the document's examples do.
      j.words = {c == Command::run_forward ? kCmdForward : kCmdReverse, frequency_};
      break;
    case Command::stop:
    case Command::quick_stop:  // the document has no faster stop than 0x0001
      j.words = {kCmdStop};
      break;
    case Command::reset_fault:
      j.op = Op::write_reset;
      j.reg = config_.reset_register;
      j.words = {config_.reset_value};
      break;
  }
  return queue_write(std::move(j), t);
}

WriteStatus Ed3100Driver::setpoint(std::int32_t rpm, Ticket t, TimePoint now) {
  last_now_ = now;
  const auto centi = centi_hz_from_rpm(rpm);
  if (!centi) return WriteStatus::invalid_value;
  return set_frequency(*centi, rpm, t);
}

WriteStatus Ed3100Driver::set_frequency(std::uint16_t centi_hz, std::int32_t rpm, Ticket t) {
  common_.setpoint_rpm = rpm;
  frequency_ = centi_hz;
  values_[index(Fixed::frequency_setpoint)] = frequency_ * 0.01;
  // Stopped, the reference travels with the next run command (one 10 write).
  if (!common_.running && !is_run(common_.command)) return WriteStatus::done;
  return queue_write(Job::make(Op::write_frequency, 0, kRegFrequency, {frequency_}), t);
}

WriteStatus Ed3100Driver::write(std::size_t point, const Value& v, Ticket t, TimePoint now) {
  last_now_ = now;
  if (point == index(Fixed::frequency_setpoint)) {
    const long long centi = std::llround(as_double(v) * 100.0);  // 0x2001 in 0.01 Hz
    if (!std::holds_alternative<std::int64_t>(v) && !std::holds_alternative<double>(v)) {
      return WriteStatus::invalid_value;
    }
    if (centi < 0 || centi > 0xFFFF) return WriteStatus::invalid_value;
    const auto c = static_cast<std::uint16_t>(centi);
    return set_frequency(c, rpm_from_hz(c * 0.01), t);
  }
  const std::size_t first = parameter_index(config_, 0);
  if (point < first || point >= first + config_.parameters.size()) {
    return WriteStatus::invalid_value;
  }
  if (std::holds_alternative<std::monostate>(v) || std::holds_alternative<std::string>(v)) {
    return WriteStatus::invalid_value;
  }
  const double x = std::round(as_double(v));
  if (x < 0 || x > 0xFFFF) return WriteStatus::invalid_value;
  const std::size_t slot = point - first;
  return queue_write(
      Job::make(Op::write_param, slot, config_.parameters[slot], {static_cast<std::uint16_t>(x)}),
      t);
}

void Ed3100Driver::take_completions(std::vector<Completion>& out) {
  out.insert(out.end(), completions_.begin(), completions_.end());
  completions_.clear();
}

}  // namespace drivegate::ed3100
