// FramedDriver: the handshake and the poll, what comes back, and the unified block.
#include "driver.h"

#include <algorithm>
#include <cmath>

namespace drivegate::framed {
namespace {

Millis ms_of(double v, double lo, double hi) {
  if (!std::isfinite(v)) v = lo;
  return Millis(static_cast<std::int64_t>(std::llround(std::clamp(v, lo, hi))));
}

}  // namespace

FramedDriver::FramedDriver(std::shared_ptr<const Description> d, const DeviceEnv& env)
    : d_(std::move(d)),
      codec_(*d_),
      state_(*d_, env.options, env.address),
      poll_interval_(env.poll_interval),
      writes_(completions_, [this](const Writes::Entry& e, WriteResult r) { settled(e, r); }) {
  const Timing& t = d_->timing;
  const Scope s = state_.scope();
  auto poll = static_cast<double>(poll_interval_.count());
  if (t.poll_min_ms) poll = std::max(poll, *t.poll_min_ms);
  if (t.poll_max_ms) poll = std::min(poll, *t.poll_max_ms);
  poll_interval_ = Millis(static_cast<std::int64_t>(poll));
  state_.set(builtin::poll_ms, poll);
  reply_timeout_ = ms_of(t.reply_timeout_ms.num(s), 1, 60'000);
  attempts_ = static_cast<std::uint8_t>(std::clamp(std::llround(t.attempts.num(s)), 1LL, 20LL));
  confirm_ = ms_of(t.confirm_ms.num(s), 10, 3'600'000);
  traits_.comm_timeout = ms_of(t.comm_timeout_ms.num(s), 10, 3'600'000);
  traits_.inter_frame_gap = ms_of(t.gap_ms.num(s), 0, 10'000);
  // The gateway's backstop comes after the driver's own deadline, so that the driver decides.
  traits_.write_timeout = std::max(kWriteTimeoutFloor, confirm_ + Millis(500));
  char_time_ = env.char_time.count() > 0 ? env.char_time : character_time(d_->line);
  for (const Point& p : d_->points) points_.push_back(p.spec);
  values_.resize(points_.size());
  sent_.assign(d_->field_names.size(), 0.0);
  fields_.assign(d_->field_names.size(), 0.0);
  publish();
}

DriverTraits FramedDriver::traits() const {
  return traits_;
}

bool FramedDriver::ready() const {
  return !d_->unified.ready || d_->unified.ready->holds(state_.scope());
}

Millis FramedDriver::poll_period() const {
  if (d_->poll && d_->poll->every_ms) {
    return ms_of(d_->poll->every_ms->num(state_.scope()), 1, 3'600'000);
  }
  return poll_interval_;
}

// The vars a poll or keep-alive carries: those of the write under way (a frame confirmed only by
// the device's state carries its order until it shows), else those in force.
std::vector<Val> FramedDriver::line_state() const {
  std::vector<Val> vars = state_.vars();
  if (!writes_.empty() && writes_.front().sent && writes_.front().job.awaiting_state) {
    propose(writes_.front().job, vars);
  }
  return vars;
}

Exchange FramedDriver::exchange(std::size_t message, const std::vector<Val>& vars, Sent what,
                                TimePoint now, std::optional<TimePoint> deadline) {
  const Message& m = d_->messages[message];
  // A new request (the engine's resends are the same frame): the next sequence number.
  const double sequence = std::fmod(state_.num(builtin::sequence) + 1, 256.0);
  state_.set(builtin::sequence, sequence);
  std::vector<Val> with_sequence = vars;
  with_sequence[builtin::sequence] = Val::of(sequence);
  const Scope s{with_sequence, {}, {}};
  for (std::size_t i = 0; i < m.fields.size(); ++i) sent_values_[i] = m.fields[i].value.num(s);
  Exchange ex;
  ex.frame = codec_.encode(message, {sent_values_.data(), m.fields.size()});
  state_.lay_out(m, {sent_values_.data(), m.fields.size()}, sent_);
  // What sending it tells (the code last sent, ...).
  state_.assign(m.update, state_.scope_with(sent_, sent_));
  ex.reply = m.replies.empty() ? ReplyMode::none : ReplyMode::expected;
  ex.timeout = m.reply_timeout_ms ? ms_of(m.reply_timeout_ms->num(s), 1, 60'000) : reply_timeout_;
  std::uint8_t attempts = attempts_;
  if (m.attempts) {
    attempts = static_cast<std::uint8_t>(std::clamp(std::llround(m.attempts->num(s)), 1LL, 20LL));
  }
  if (deadline) {
    // Only the attempts that start before the write's deadline: a reply long after it would put
    // in force a write the gateway may have failed. The frame (and its echo), the timeout, the
    // guard after it and the gap, each.
    const auto wire = char_time_ * static_cast<long>(ex.frame.size() * (d_->line.echo ? 2 : 1));
    const Millis per =
        std::chrono::ceil<Millis>(wire + traits_.inter_frame_gap) + unanswered_attempt(ex.timeout);
    attempts = attempts_before(*deadline, now, per, attempts);
  }
  ex.attempts = attempts;
  if (ex.reply == ReplyMode::expected) {
    in_flight_ = InFlight{what, message};
  } else {
    in_flight_.reset();
  }
  // Every frame is a keep-alive: the poll is due one period after the last one went.
  next_poll_ = now + poll_period();
  publish();
  return ex;
}

std::optional<Exchange> FramedDriver::next_exchange(TimePoint now) {
  writes_.expire(now);
  in_flight_.reset();
  if (!ready()) {
    const bool waiting_writes = !writes_.empty() && d_->timing.writes_wait_for_ready;
    if (d_->init && (now >= next_init_ || waiting_writes) &&
        (!d_->init->when || d_->init->when->holds(state_.scope()))) {
      const double every = d_->init->every_ms ? d_->init->every_ms->num(state_.scope()) : 0.0;
      next_init_ = now + ms_of(every, 0, 3'600'000);
      return exchange(d_->init->send, state_.vars(), Sent::init, now, std::nullopt);
    }
    return std::nullopt;
  }
  if (auto w = next_write(now)) return w;
  if (!d_->poll) return std::nullopt;
  if (!poll_now_ && now < next_poll_) return std::nullopt;
  if (d_->poll->when && !d_->poll->when->holds(state_.scope())) return std::nullopt;
  poll_now_ = false;
  return exchange(d_->poll->send, line_state(), Sent::poll, now, std::nullopt);
}

TimePoint FramedDriver::wake_at() const {
  TimePoint t = TimePoint::max();
  const bool rdy = ready();
  if (!rdy && d_->init) t = std::min(t, next_init_);
  const bool unsent = !writes_.empty() && !writes_.front().sent;
  if (unsent && (rdy || (d_->init && d_->timing.writes_wait_for_ready))) return TimePoint::min();
  if (rdy && d_->poll) t = std::min(t, poll_now_ ? TimePoint::min() : next_poll_);
  if (const auto deadline = writes_.next_deadline()) t = std::min(t, *deadline);
  return t;
}

// Whether `reply` answers the request in flight: one of its replies, its echoed fields equal.
bool FramedDriver::answers(const Message& reply, const Frame& f) const {
  if (!in_flight_) return false;
  const Message& req = d_->messages[in_flight_->message];
  const auto index = static_cast<std::size_t>(&reply - d_->messages.data());
  if (std::find(req.replies.begin(), req.replies.end(), index) == req.replies.end()) return false;
  return std::all_of(reply.echo.begin(), reply.echo.end(),
                     [&](const auto& e) { return codec_.value(f, e.first) == sent_[e.second]; });
}

RxVerdict FramedDriver::on_receive(ByteView rx, TimePoint now) {
  writes_.expire(now);
  const Decoded<Frame> d = codec_.decode(Direction::reply, rx);
  if (const auto v = unless_frame(d)) return *v;
  const Message& m = d_->messages[d.frame.message];
  if (m.nack) return {RxKind::nack, d.consumed};  // the engine resends
  const bool awaited = answers(m, d.frame);
  if (!awaited && !m.unsolicited) return {RxKind::foreign, d.consumed};
  std::array<double, kMaxFields> values{};
  codec_.values(d.frame, values);
  state_.lay_out(m, {values.data(), m.fields.size()}, fields_);
  state_.assign(m.update, state_.scope_with(fields_, sent_));
  RxKind kind = RxKind::frame;
  if (awaited) {
    kind = m.state ? RxKind::reply : RxKind::ack;
    const Sent what = in_flight_->what;
    in_flight_.reset();
    if (what == Sent::write) on_reply_to_write(d.frame);
  }
  refresh(now);
  return {kind, d.consumed};
}

void FramedDriver::on_no_reply(TimePoint now) {
  (void)now;
  if (in_flight_ && in_flight_->what == Sent::write && writes_.front_on_line()) {
    // Resent while its deadline lets it (the next turn), as the protocols ask of a lost reply.
    writes_.front().sent = false;
  }
  in_flight_.reset();
}

void FramedDriver::on_comm_lost(TimePoint now) {
  in_flight_.reset();
  for (std::size_t i = 0; i < d_->vars.size(); ++i) {
    const Var& v = d_->vars[i];
    if (v.reset_on_comm_lost) state_.set(i, v.reset_value.num);
  }
  writes_.settle_all(WriteResult::no_response);
  // The drive stops by itself when the line goes quiet: no run is in force any more.
  if (d_->unified.comm_lost_stops && is_run(static_cast<Command>(state_.num(builtin::command)))) {
    state_.set(builtin::command, static_cast<double>(Command::stop));
  }
  next_init_ = now;
  next_poll_ = now;
  refresh(now);
}

// After the state changed: derived points, what a write waited for, readiness and the block.
void FramedDriver::refresh(TimePoint now) {
  state_.derive();
  // The drive stopped a run by itself (a fault, a brake): it is no longer in force.
  if (d_->unified.stops_run && d_->unified.stops_run->holds(state_.scope()) &&
      is_run(static_cast<Command>(state_.num(builtin::command)))) {
    state_.set(builtin::command, static_cast<double>(Command::stop));
  }
  confirm_by_state();
  const bool rdy = ready();
  if (rdy && !was_ready_ && d_->poll && d_->poll->at_ready) next_poll_ = now;
  was_ready_ = rdy;
  publish();
}

void FramedDriver::publish() {
  const Scope s = state_.scope();
  const Unified& u = d_->unified;
  common_.ready = ready();
  common_.command = static_cast<Command>(std::clamp(state_.num(builtin::command), 0.0, 4.0));
  common_.setpoint_rpm = static_cast<std::int32_t>(std::llround(state_.num(builtin::setpoint)));
  common_.speed_rpm =
      u.speed_rpm ? static_cast<std::int32_t>(std::llround(u.speed_rpm->num(s))) : 0;
  common_.warning = u.warning && u.warning->holds(s);
  const double native = u.native_fault ? u.native_fault->num(s) : 0.0;
  common_.native_fault = static_cast<std::uint32_t>(std::clamp(native, 0.0, 4294967295.0));
  common_.faults = FaultSet{};
  for (const FaultRule& r : u.faults) {
    if (r.when) {
      if (r.when->holds(s)) common_.faults.set(r.fault);
      continue;
    }
    const auto v = static_cast<std::uint32_t>(std::clamp(r.source->num(s), 0.0, 4294967295.0));
    bool named = false;
    for (const auto& [mask, f] : r.bits) {
      if ((v & mask) != 0) {
        common_.faults.set(f);
        named = true;
      }
    }
    for (const auto& [value, f] : r.values) {
      if (v == value) {
        common_.faults.set(f);
        named = true;
      }
    }
    for (const auto& range : r.ranges) {
      if (v >= range.lo && v <= range.hi) {
        common_.faults.set(range.fault);
        named = true;
      }
    }
    if (v != 0 && !named && r.other) common_.faults.set(*r.other);
  }
  common_.running =
      u.running ? u.running->holds(s) : is_run(common_.command) || common_.speed_rpm != 0;
  for (std::size_t i = 0; i < values_.size(); ++i) values_[i] = state_.point_value(i);
}

}  // namespace drivegate::framed
