// NidecWasherDriver: the ping handshake, the poll plan, and what the bus engine hands back.
#include "driver.h"

#include <algorithm>
#include <chrono>

namespace drivegate::nidec {
namespace {

constexpr Millis kReplyTimeout{100};  // section 6: resend after 100 ms without a reply
constexpr Millis kCommTimeout{6000};  // section 6: no reply for 6 s = communication fault
constexpr Millis kMaxPoll{1000};      // 5.2 / section 6: a frame every second at least
constexpr Millis kMinPoll{10};        // not in the document: below this the line is only polls
// Not in the document: two characters of line silence before each frame (4.6 ms at 4800 8O1),
// so that the inverter sees where one frame ends and the next begins.
constexpr Millis kInterFrameGap = std::chrono::ceil<Millis>(2 * character_time(kLine));
// The gateway fails a write still pending after this (0x0B); the driver's own confirmation
// deadline (driver_writes.cpp) comes before it.
constexpr Millis kWriteTimeout{3000};

// The longest one attempt at a frame of `bytes` takes: the frame and its echo on the native line
// (section 3; the engine waits for the echo before it times the reply), the 100 ms reply timeout
// (section 6) and the engine's guard time after it, and the gap before the next attempt.
Millis attempt_time(std::size_t bytes) {
  const auto wire = character_time(kLine) * static_cast<long>(2 * bytes);
  return std::chrono::ceil<Millis>(wire) + unanswered_attempt(kReplyTimeout) + kInterFrameGap;
}

// Not in the document (see README): 0.5 s ramps, 1.2 s on, 0.8 s off each way.
constexpr AgitationTiming kDefaultAgitation{5, 5, 12, 8, 12, 8};

}  // namespace

NidecWasherDriver::NidecWasherDriver(const Settings& settings, Millis poll_interval)
    : settings_(settings),
      poll_interval_(std::clamp(poll_interval, kMinPoll, kMaxPoll)),
      accel_100ms_(settings.accel_100ms),
      agitation_(kDefaultAgitation) {
  points_ = make_points();
  values_.resize(pt::count);
  values_[pt::motion] = std::int64_t{static_cast<std::int64_t>(motion_)};
  values_[pt::accel_time] = seconds_of(accel_100ms_);
  values_[pt::agitation_accel] = seconds_of(agitation_.accel);
  values_[pt::agitation_decel] = seconds_of(agitation_.decel);
  values_[pt::agitation_cw_on] = seconds_of(agitation_.cw_on);
  values_[pt::agitation_cw_off] = seconds_of(agitation_.cw_off);
  values_[pt::agitation_ccw_on] = seconds_of(agitation_.ccw_on);
  values_[pt::agitation_ccw_off] = seconds_of(agitation_.ccw_off);
  values_[pt::action] = std::int64_t{static_cast<std::int64_t>(Action::none)};
  values_[pt::action_status] = std::int64_t{static_cast<std::int64_t>(ActionStatus::idle)};
}

DriverTraits NidecWasherDriver::traits() const {
  return {kCommTimeout, kWriteTimeout, kInterFrameGap};
}

Exchange NidecWasherDriver::exchange(const Request& r) const {
  Exchange ex;
  ex.frame = encode(r);
  ex.reply = ReplyMode::expected;  // 5.16: the inverter answers every frame, an ACK or a NACK
  ex.timeout = kReplyTimeout;
  ex.attempts = settings_.attempts;
  return ex;
}

std::optional<Exchange> NidecWasherDriver::next_exchange(TimePoint now) {
  queue_.expire(now);
  if (!common_.ready) {
    // 5.1: the ping goes after every start or reconnect, before anything else; writes wait
    // behind it (and make the engine ask at once: the device has writes pending).
    if (next_poll_ && now < *next_poll_ && queue_.empty()) return std::nullopt;
    in_flight_ = InFlight::ping;
    expected_ = Mode::ping;
    last_sent_ = now;
    return exchange(make_ping(settings_.platform, settings_.empty_raw_weight));
  }
  if (const Writes::Entry* q = front_to_send()) {
    in_flight_ = InFlight::queued;
    expected_ = q->job.request->mode;
    last_sent_ = now;
    Exchange ex = exchange(*q->job.request);
    // Only the attempts that start before the write's deadline (expire() has kept it, so one at
    // least): an ACK long after it would put in force a write the gateway may have failed.
    ex.attempts =
        attempts_before(q->deadline, now, attempt_time(ex.frame.size()), settings_.attempts);
    return ex;
  }
  if (next_poll_ && now < *next_poll_) return std::nullopt;
  in_flight_ = InFlight::poll;
  expected_ = Mode::request;
  last_sent_ = now;
  return exchange(make_bare(Mode::request));  // 5.2
}

TimePoint NidecWasherDriver::wake_at() const {
  if (!queue_.empty()) return TimePoint::min();
  return next_poll_.value_or(TimePoint::min());
}

RxVerdict NidecWasherDriver::on_receive(ByteView rx, TimePoint now) {
  (void)now;
  const Decoded<Reply> d = decode_reply(rx);
  if (const auto v = unless_frame(d)) return *v;
  if (d.frame.nack) return {RxKind::nack, d.consumed};  // 5.16: the engine resends
  // Section 2: the inverter only ever answers the frame just sent, so a good frame of another
  // mode is a late answer to an earlier one.
  if (in_flight_ == InFlight::none || d.frame.mode != expected_) {
    return {RxKind::foreign, d.consumed};
  }
  apply_reply(d.frame);
  if (in_flight_ == InFlight::ping) common_.ready = true;
  if (in_flight_ == InFlight::queued) complete_front(d.frame);
  in_flight_ = InFlight::none;
  // Section 6: the next frame one poll interval after this one went, whatever it was.
  next_poll_ = last_sent_ + poll_interval_;
  update_running();
  return {RxKind::reply, d.consumed};
}

void NidecWasherDriver::on_no_reply(TimePoint now) {
  // Section 6: resend the same frame (a queued write stays at the front until it is answered or
  // its deadline passes); the engine backs off a silent device.
  in_flight_ = InFlight::none;
  next_poll_ = now;
}

void NidecWasherDriver::on_comm_lost(TimePoint now) {
  (void)now;
  common_.ready = false;
  in_flight_ = InFlight::none;
  next_poll_.reset();
  queue_.settle_all(WriteResult::no_response);
  // Section 7: after 6 s without bus activity the inverter stops the motor by itself.
  common_.speed_rpm = 0;
  set_command(Command::stop);
}

void NidecWasherDriver::set_command(Command c) {
  common_.command = c;
  update_running();
}

void NidecWasherDriver::update_running() {
  common_.running = is_run(common_.command) || common_.speed_rpm != 0;
}

}  // namespace drivegate::nidec
