#include "driver.h"

#include <algorithm>
#include <cmath>

#include "faults.h"

namespace drivegate::nidec {
namespace {

constexpr Millis kReplyTimeout{100};   // section 6: resend after 100 ms without a reply
constexpr Millis kCommTimeout{6000};   // section 6: no reply for 6 s = communication fault
constexpr Millis kMaxPoll{1000};       // 5.2 / section 6: poll every 1 s at least
constexpr Millis kInterFrameGap{5};    // not in the document: about two byte times at 4800 baud
constexpr Millis kWriteTimeout{3000};  // the gateway's 0x0B deadline; ours fires before it

// Default agitation pattern (not in the document; see README): 0.5 s ramps, 1.2 s on, 0.8 s off.
constexpr AgitationTiming kDefaultAgitation{5, 5, 12, 8, 12, 8};

bool is_run(Command c) {
  return c == Command::run_forward || c == Command::run_reverse;
}

std::uint16_t clamp16(std::int64_t v) {
  return static_cast<std::uint16_t>(std::clamp<std::int64_t>(v, 0, 0xFFFF));
}

double tenths(std::int64_t units) {
  return static_cast<double>(units) / 10.0;
}

}  // namespace

DriverConfig config_from(const DeviceEnv& env) {
  DriverConfig c;
  const Options& o = env.options;
  if (o.has("platform")) c.platform = static_cast<std::uint8_t>(o.integer("platform"));
  if (o.has("empty_raw_weight")) c.empty_raw_weight = clamp16(o.integer("empty_raw_weight"));
  if (o.has("accel_time_ms")) c.accel_100ms = clamp16((o.integer("accel_time_ms") + 50) / 100);
  if (o.has("attempts")) c.attempts = static_cast<std::uint8_t>(o.integer("attempts"));
  c.poll_interval = std::clamp(env.poll_interval, Millis{10}, kMaxPoll);
  return c;
}

WasherDriver::WasherDriver(const DriverConfig& config)
    : config_(config),
      points_(make_points()),
      values_(pt::count),
      accel_100ms_(config.accel_100ms),
      agitation_(kDefaultAgitation) {
  values_[pt::motion] = std::int64_t{0};
  values_[pt::accel_time] = tenths(accel_100ms_);
  values_[pt::agitation_accel] = tenths(agitation_.accel);
  values_[pt::agitation_decel] = tenths(agitation_.decel);
  values_[pt::agitation_cw_on] = tenths(agitation_.cw_on);
  values_[pt::agitation_cw_off] = tenths(agitation_.cw_off);
  values_[pt::agitation_ccw_on] = tenths(agitation_.ccw_on);
  values_[pt::agitation_ccw_off] = tenths(agitation_.ccw_off);
  values_[pt::action] = std::int64_t{0};
  values_[pt::action_status] = std::int64_t{0};
}

DriverTraits WasherDriver::traits() const {
  return {kCommTimeout, kWriteTimeout, kInterFrameGap};
}

Exchange WasherDriver::exchange(const Request& r, Priority p) const {
  Exchange ex;
  ex.frame = encode(r);
  ex.reply = ReplyMode::expected;
  ex.timeout = kReplyTimeout;
  ex.attempts = config_.attempts;
  ex.priority = p;
  return ex;
}

std::optional<Exchange> WasherDriver::next_exchange(TimePoint now) {
  expire(now);
  if (!ready_) {
    // 5.1: ping after every start or reconnect, before anything else.
    if (next_poll_ && now < *next_poll_ && queue_.empty()) return std::nullopt;
    in_flight_ = InFlight::ping;
    expected_ = Mode::ping;
    last_sent_ = now;
    return exchange(make_ping(config_.platform, config_.empty_raw_weight),
                    queue_.empty() ? Priority::poll : Priority::command);
  }
  if (!queue_.empty()) {
    in_flight_ = InFlight::queued;
    expected_ = queue_.front().request.mode;
    last_sent_ = now;
    return exchange(queue_.front().request, Priority::command);
  }
  if (next_poll_ && now < *next_poll_) return std::nullopt;
  in_flight_ = InFlight::poll;
  expected_ = Mode::request;
  last_sent_ = now;
  return exchange(make_bare(Mode::request), Priority::poll);  // 5.2
}

TimePoint WasherDriver::wake_at() const {
  if (!queue_.empty()) return TimePoint::min();
  return next_poll_.value_or(TimePoint::min());
}

RxVerdict WasherDriver::on_receive(ByteView rx, TimePoint now) {
  (void)now;
  const Decoded<Reply> d = decode_reply(rx);
  if (d.status == DecodeStatus::incomplete) return {RxKind::incomplete, 0};
  if (d.status == DecodeStatus::bad) {
    const bool checksum = d.error == make_error_code(FrameError::bad_checksum);
    return {checksum ? RxKind::bad_checksum : RxKind::noise, d.consumed};
  }
  if (d.frame.nack) return {RxKind::nack, d.consumed};  // 5.16: the engine resends
  // The inverter only ever answers the frame just sent (section 2): anything else is stale.
  if (in_flight_ == InFlight::none || d.frame.mode != expected_) {
    return {RxKind::foreign, d.consumed};
  }
  apply(d.frame);
  if (in_flight_ == InFlight::ping) ready_ = common_.ready = true;
  if (in_flight_ == InFlight::queued) complete_front(d.frame);
  in_flight_ = InFlight::none;
  next_poll_ = last_sent_ + config_.poll_interval;
  update_running();
  return {RxKind::reply, d.consumed};
}

void WasherDriver::on_no_reply(TimePoint now) {
  // Section 6: keep resending the same frame (a queued write stays at the front until its
  // deadline); the engine backs off a silent device on a shared bus.
  in_flight_ = InFlight::none;
  next_poll_ = now;
}

void WasherDriver::on_comm_lost(TimePoint now) {
  (void)now;
  ready_ = common_.ready = false;
  in_flight_ = InFlight::none;
  next_poll_.reset();
  while (!queue_.empty()) {
    const Queued q = queue_.front();
    queue_.pop_front();
    finish(q, WriteResult::no_response);
  }
  // Section 7: after 6 s without bus activity the inverter stops the motor by itself.
  set_command(Command::stop);
  common_.speed_rpm = 0;
  update_running();
}

void WasherDriver::expire(TimePoint now) {
  for (auto it = queue_.begin(); it != queue_.end();) {
    if (it->deadline <= now) {
      const Queued q = *it;
      it = queue_.erase(it);
      finish(q, WriteResult::no_response);
    } else {
      ++it;
    }
  }
}

void WasherDriver::finish(const Queued& q, WriteResult result) {
  completions_.push_back({q.ticket, result});
  if (q.job == Job::action) {
    const ActionStatus s =
        result == WriteResult::ok ? ActionStatus::done : ActionStatus::no_response;
    values_[pt::action_status] = static_cast<std::int64_t>(s);
  }
}

void WasherDriver::complete_front(const Reply& r) {
  if (queue_.empty()) return;
  const Queued q = queue_.front();
  queue_.pop_front();
  switch (q.job) {
    case Job::run:
      // Section 8: a faulted inverter keeps the motor stopped; its ACK carries the Error bits.
      if (r.error() != 0) return finish(q, WriteResult::refused);
      motion_in_force_ = q.motion;
      set_command(q.command);
      return finish(q, WriteResult::ok);
    case Job::stop:
      set_command(q.command);
      return finish(q, WriteResult::ok);
    case Job::reset_fault:
      // There is no reset frame: a Request tells whether the inverter has cleared the fault.
      return finish(q, r.error() == 0 ? WriteResult::ok : WriteResult::refused);
    case Job::action:
      return finish(q, WriteResult::ok);
  }
}

void WasherDriver::set_command(Command c) {
  common_.command = c;
  update_running();
}

void WasherDriver::update_running() {
  common_.running = is_run(common_.command) || common_.speed_rpm != 0;
}

void WasherDriver::take_completions(std::vector<Completion>& out) {
  out.insert(out.end(), completions_.begin(), completions_.end());
  completions_.clear();
}

}  // namespace drivegate::nidec
