#include "bus/bus_engine.h"

#include <spdlog/fmt/bin_to_hex.h>

#include <algorithm>

namespace drivegate {

namespace {
// A reply buffer that grows past this without a frame is line garbage, not a frame in progress.
constexpr std::size_t kMaxRxBuffer = 4096;
// An idle line looks again at least this often, whatever the devices said.
constexpr Millis kLongestIdle{1000};
// The echo of a one-wire frame is back once the frame has crossed the wire, plus this margin
// (two characters and the UART's and kernel's latency).
constexpr std::size_t kEchoSlackChars = 2;
constexpr Millis kEchoSlack{50};
// Late bytes extend the guard time after a reply timeout, but a line that never falls quiet
// (noise, a babbling device) holds the next frame back at most this many guard times.
constexpr int kGuardLimit = 4;
// The most a device's lateness may lengthen its guard time: a drive later than this is as good
// as silent, and every one of its turns would cost its neighbours that much line time.
constexpr Millis kMaxGuard{1000};

// How a capture flags a frame the station judged `kind`.
std::uint8_t verdict_flags(RxKind kind) {
  switch (kind) {
    case RxKind::bad_checksum:
      return frame_flags::bad_checksum;
    case RxKind::nack:
      return frame_flags::nack;
    case RxKind::foreign:
      return frame_flags::foreign;
    case RxKind::noise:
      return frame_flags::noise;
    default:
      return 0;
  }
}
}  // namespace

BusEngine::BusEngine(const BusConfig& config, std::vector<Station*> stations, BusClock& clock,
                     BusLine& line, std::shared_ptr<spdlog::logger> log)
    : name_(config.name),
      echo_line_(config.echo),
      network_delay_(config.network_delay),
      char_time_(character_time(config.baud, config.parity, config.data_bits, config.stop_bits)),
      stations_(std::move(stations)),
      clock_(clock),
      line_(line),
      log_(std::move(log)) {
  for (Station* st : stations_) {
    if (st->link().policy.streaming) streaming_ = st;
    st->link().bus = &counters_;
  }
}

BusEngine::~BusEngine() = default;

void BusEngine::start() {
  if (started_) return;
  started_ = true;
  for (Station* st : stations_) st->on_work([this] { kick(); });
  next_tick_ = clock_.now();
  clock_.set_alarm(next_tick_);
}

void BusEngine::replace_stations(std::vector<Station*> stations) {
  const TimePoint now = clock_.now();
  for (Station* st : stations_) {
    if (std::find(stations.begin(), stations.end(), st) != stations.end()) continue;
    if (started_) st->on_work(nullptr);
    if (guard_owner_ == st) guard_owner_ = nullptr;  // its late bytes are only noise now
    if (st != current_) continue;
    // Its reply may still come: nothing is sent before it could have, and none of it is taken.
    quiet_until_ = std::max(quiet_until_, now + exchange_->timeout + network_delay_);
    exchange_.reset();
    current_ = nullptr;
    echo_.clear();
    if (state_ != State::down) state_ = State::idle;
  }
  stations_ = std::move(stations);
  streaming_ = nullptr;
  for (Station* st : stations_) {
    if (st->link().policy.streaming) streaming_ = st;
    st->link().bus = &counters_;
    if (started_) st->on_work([this] { kick(); });
  }
  next_station_ = 0;
  if (started_) kick();
}

void BusEngine::stop() {
  if (!started_) return;
  started_ = false;
  state_ = State::down;
  exchange_.reset();
  current_ = nullptr;
  for (Station* st : stations_) st->on_work(nullptr);
}

void BusEngine::add_tap(FrameTap* tap) {
  if (tap != nullptr && std::find(taps_.begin(), taps_.end(), tap) == taps_.end()) {
    taps_.push_back(tap);
  }
}

void BusEngine::remove_tap(FrameTap* tap) {
  taps_.erase(std::remove(taps_.begin(), taps_.end(), tap), taps_.end());
}

void BusEngine::kick() {
  kicked_ = true;
  if (started_) clock_.set_alarm(clock_.now());
}

// --- the line opening and failing ---

void BusEngine::line_up(bool reopened) {
  if (!started_) return;
  const TimePoint now = clock_.now();
  if (reopened) ++counters_.reopens;
  state_ = State::idle;
  rx_.clear();
  last_activity_ = now;
  pump(now);
  rearm(now);
}

void BusEngine::line_down() {
  if (!started_ || state_ == State::down) return;
  const TimePoint now = clock_.now();
  if (Station* st = current_; st != nullptr) {
    exchange_.reset();
    current_ = nullptr;
    st->on_no_reply(now);
    st->link().health.turn_failed(now, st->link().policy);
  }
  state_ = State::down;
  echo_.clear();
  quiet_until_ = {};
  guard_owner_ = nullptr;
  rearm(now);
}

// --- time ---

void BusEngine::on_alarm() {
  if (!started_) return;
  const TimePoint now = clock_.now();
  if (now >= next_tick_) {
    tick(now);
    next_tick_ = now + kTickPeriod;
  }
  const bool waiting =
      state_ == State::gap || state_ == State::awaiting_echo || state_ == State::awaiting_reply;
  if (waiting && now >= deadline_) on_deadline(now);
  if (state_ == State::idle) pump(now);
  rearm(now);
}

void BusEngine::tick(TimePoint now) {
  for (Station* st : stations_) {
    Link& link = st->link();
    if (link.health.lost_by(now, link.policy.comm_timeout)) {
      link.log->warn("device {}: no good frame for {} ms: comm_lost", st->name(),
                     link.policy.comm_timeout.count());
      st->on_comm_lost(now);
    }
    st->on_tick(now);
  }
}

void BusEngine::rearm(TimePoint now) {
  TimePoint at = next_tick_;
  switch (state_) {
    case State::gap:
    case State::awaiting_echo:
    case State::awaiting_reply:
      at = std::min(at, deadline_);
      break;
    case State::idle:
      at = std::min(at, kicked_ ? now : idle_wake(now));
      break;
    case State::sending:  // on_sent() comes
    case State::down:     // line_up() comes
      break;
  }
  clock_.set_alarm(at);
}

// The earliest a device wants the line: its driver's wake-up, or its next probe when backed off.
TimePoint BusEngine::idle_wake(TimePoint now) const {
  TimePoint wake = now + kLongestIdle;
  for (Station* st : stations_) {
    const LinkHealth& h = st->link().health;
    const TimePoint w = h.in_backoff(now) ? h.probe_at() : st->wake_at();
    wake = std::min(wake, std::max(w, now + Millis(1)));
  }
  return wake;
}

void BusEngine::on_deadline(TimePoint now) {
  switch (state_) {
    case State::gap:
      send_attempt(now);
      return;
    case State::awaiting_reply: {
      ++counters_.timeouts;
      Link& link = current_->link();
      ++link.counters.timeouts;
      link.log->debug("bus {}: device {} did not answer (attempt {} of {})", name_,
                      current_->name(), attempt_ + 1, max_attempts_);
      timed_out_ = true;
      start_guard(*current_, now);
      attempt_failed(now);
      return;
    }
    case State::awaiting_echo:
      ++counters_.echo_errors;
      log_->debug("bus {}: our own frame did not come back (one-wire line broken?)", name_);
      attempt_failed(now);
      return;
    default:
      return;
  }
}

// --- transmitting ---

// Urgent writes first; then, when writes and polls both wait, whichever did not have the last
// turn: a write storm takes at most every other exchange of the line.
void BusEngine::pump(TimePoint now) {
  if (state_ != State::idle || stations_.empty()) return;
  kicked_ = false;
  if (take_turn(Pick::urgent, now)) return;
  const Pick first = last_turn_was_write_ ? Pick::poll : Pick::write;
  if (take_turn(first, now)) return;
  take_turn(first == Pick::poll ? Pick::write : Pick::poll, now);
}

// One turn of `pick`, round-robin from where the last turn ended; false when nobody wanted it.
bool BusEngine::take_turn(Pick pick, TimePoint now) {
  const std::size_t n = stations_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t idx = (next_station_ + i) % n;
    Station& st = *stations_[idx];
    const PendingWrites writes = st.pending_writes(now);
    switch (pick) {
      case Pick::urgent:
        if (writes != PendingWrites::urgent) continue;
        break;
      case Pick::write:
        if (writes == PendingWrites::none) continue;
        break;
      case Pick::poll:
        if (st.link().health.in_backoff(now) || st.wake_at() > now) continue;
        break;
    }
    if (std::optional<Exchange> ex =
            st.next_exchange(now, pick == Pick::poll ? Turn::poll : Turn::write)) {
      next_station_ = (idx + 1) % n;
      last_turn_was_write_ = pick != Pick::poll;
      begin(st, std::move(*ex), now);
      return true;
    }
  }
  return false;
}

void BusEngine::begin(Station& st, Exchange ex, TimePoint now) {
  current_ = &st;
  exchange_ = std::move(ex);
  attempt_ = 0;
  // The device's time budget caps how many attempts one turn may take: each costs its time on
  // the wire, the reply timeout and, when it times out, the guard time after it (none on a
  // streaming line).
  const auto wire = on_wire(exchange_->frame.size()) * (echo_line_ ? 2 : 1);
  const Millis wait = exchange_->timeout + network_delay_;
  const Millis guard = streaming_ == nullptr ? guard_for(st.link(), wait) : Millis(0);
  const auto per_attempt = std::chrono::duration_cast<Millis>(wait + guard + wire) + Millis(1);
  const auto fit = static_cast<int>(st.link().policy.budget / per_attempt);
  max_attempts_ = std::clamp(fit, 1, std::max<int>(1, exchange_->attempts));
  answered_ = false;
  timed_out_ = false;
  ++counters_.exchanges;
  send_attempt(now);
}

void BusEngine::send_attempt(TimePoint now) {
  if (const TimePoint at = clear_at(current_->link().policy.inter_frame_gap); now < at) {
    state_ = State::gap;
    deadline_ = at;
    return;
  }
  guard_owner_ = nullptr;
  if (attempt_ == 0) first_sent_ = now;
  last_sent_ = now;
  state_ = State::sending;
  const Bytes& frame = exchange_->frame;
  echo_ = echo_line_ ? frame : Bytes{};
  echo_broken_ = false;
  if (streaming_ == nullptr) {
    tap(FrameDirection::from_drive, frame_flags::noise, current_, rx_, now);  // a reply cut short
    rx_.clear();
  }
  log_->trace("bus {}: tx {:n}", name_, spdlog::to_hex(frame));
  tap(FrameDirection::to_drive, attempt_ > 0 ? frame_flags::retry : 0, current_, frame, now);
  counters_.bytes_sent += frame.size();
  line_.send(frame);
}

void BusEngine::on_sent() {
  if (!started_ || state_ != State::sending) return;
  const TimePoint now = clock_.now();
  // The kernel has the bytes; they leave the UART over the frame's time on the wire, and the gap
  // before the next frame counts from then (on a one-wire line the echo shows it).
  note_activity(echo_line_ ? now : now + on_wire(exchange_->frame.size()));
  if (echo_line_) {
    state_ = State::awaiting_echo;
    deadline_ =
        now +
        std::chrono::duration_cast<Millis>(on_wire(exchange_->frame.size() + kEchoSlackChars)) +
        kEchoSlack + network_delay_;
    advance(now);
  } else {
    after_sent(now);
  }
  rearm(now);
}

void BusEngine::after_sent(TimePoint now) {
  if (exchange_->reply == ReplyMode::none) {
    finish(now);
    return;
  }
  state_ = State::awaiting_reply;
  // The write completes when the kernel has the bytes, not when they have left the UART; on a
  // one-wire line the echo has already shown them leave.
  const auto wire = echo_line_ ? std::chrono::nanoseconds(0) : on_wire(exchange_->frame.size());
  // Behind a serial device server the reply also crosses the network (network_delay_ms).
  deadline_ = now + exchange_->timeout + network_delay_ + std::chrono::duration_cast<Millis>(wire);
  if (!rx_.empty()) process_rx(*current_, now);
}

void BusEngine::attempt_failed(TimePoint now) {
  if (++attempt_ < max_attempts_) {
    ++counters_.retries;
    ++current_->link().counters.retries;
    send_attempt(now);
    return;
  }
  // A device that NACKs or answers garbled is there: keep its poll rate, back off only silence.
  unanswered(now, !answered_);
}

Station* BusEngine::release() {
  Station* st = current_;
  exchange_.reset();
  current_ = nullptr;
  state_ = State::idle;
  echo_.clear();
  return st;
}

void BusEngine::finish(TimePoint now) {
  release();
  pump(now);
}

void BusEngine::unanswered(TimePoint now, bool silent) {
  note_held(*current_, now);
  Station* st = release();
  st->on_no_reply(now);
  if (silent) st->link().health.turn_failed(now, st->link().policy);
  pump(now);
}

// A turn that ran into a reply timeout held the line from its first frame until the guard time
// after it ends: the device waits for its next poll turn for a multiple of that. A device alone
// on its line has no neighbour to leave the time to: it keeps the cadence its protocol gives
// (its resends, its silence back-off) and pays nothing more.
void BusEngine::note_held(Station& st, TimePoint now) {
  if (!timed_out_ || stations_.size() < 2) return;
  st.link().health.turn_held(now, std::max(now, quiet_until_) - first_sent_);
}

// --- receiving ---

void BusEngine::on_received(ByteView bytes) {
  if (!started_ || state_ == State::down || bytes.empty()) return;
  const TimePoint now = clock_.now();
  note_activity(now);
  counters_.bytes_received += bytes.size();
  log_->trace("bus {}: rx {:n}", name_, spdlog::to_hex(bytes.begin(), bytes.end()));
  const bool in_exchange =
      exchange_ && (state_ == State::sending || state_ == State::awaiting_echo ||
                    state_ == State::awaiting_reply);
  if (!in_exchange && streaming_ == nullptr) {
    if (guard_owner_ != nullptr && now < quiet_until_) {
      late_bytes(bytes, now);
    } else {
      tap(FrameDirection::from_drive, frame_flags::noise, nullptr, bytes, now);
      counters_.noise_bytes += static_cast<std::uint32_t>(bytes.size());  // line noise
    }
    rearm(now);
    return;
  }
  rx_.insert(rx_.end(), bytes.begin(), bytes.end());
  if (in_exchange) {
    advance(now);
  } else {
    process_rx(*streaming_, now);
  }
  rearm(now);
}

// A reply timed out: nothing is sent for a guard time, so that a reply still on its way is not
// taken for the answer to what is sent next. Not on a streaming line, whose bytes are the
// stream's.
void BusEngine::start_guard(Station& owner, TimePoint now) {
  if (streaming_ != nullptr) return;
  const Link& link = owner.link();
  guard_ = guard_for(link, exchange_->timeout + network_delay_);
  guard_owner_ = &owner;
  guard_last_sent_ = last_sent_;
  guard_spread_ = last_sent_ - first_sent_;
  guard_started_ = now;
  // A device known to answer late may still answer every attempt of this exchange.
  const auto spread =
      link.health.lateness().count() > 0 ? guard_spread_ : decltype(guard_spread_){};
  quiet_until_ = now + guard_ + spread;
}

// The guard time after a timeout of the device on `link`: the reply timeout again, or the
// lateness the device has shown (at most kMaxGuard), whichever is longer.
Millis BusEngine::guard_for(const Link& link, Millis wait) {
  return std::max(guard_time(wait), std::min(link.health.lateness(), kMaxGuard));
}

// Bytes in the guard time: a late reply. Dropped and counted. The device answers late: its
// lateness is noted (at least the time since its exchange's last frame), a resend of that
// exchange waiting for the quiet is given up, and the quiet lasts until replies to all its
// attempts can have come: from these bytes, the guard (now at least that lateness) and the
// time between the exchange's first and last frame, within kGuardLimit of such spans.
void BusEngine::late_bytes(ByteView bytes, TimePoint now) {
  tap(FrameDirection::from_drive, frame_flags::noise, guard_owner_, bytes, now);
  const auto n = static_cast<std::uint32_t>(bytes.size());
  counters_.late_bytes += n;
  Link& link = guard_owner_->link();
  link.counters.late_bytes += n;
  const Millis lateness =
      std::min(std::chrono::duration_cast<Millis>(now - guard_last_sent_), kMaxGuard);
  link.health.saw_late(lateness);
  guard_ = std::max<std::chrono::nanoseconds>(guard_, lateness);
  const auto span = guard_ + guard_spread_;
  quiet_until_ = std::min(guard_started_ + kGuardLimit * span, std::max(quiet_until_, now + span));
  if (state_ != State::gap) return;
  if (current_ == guard_owner_ && attempt_ > 0) {
    give_up(now);
    return;
  }
  deadline_ = clear_at(current_->link().policy.inter_frame_gap);
}

// The device in the exchange waiting to be resent answers, but late: no more attempts; it counts
// as a turn without an answer (backed off like a silent device).
void BusEngine::give_up(TimePoint now) {
  unanswered(now, true);
}

// Moves an exchange forward with what rx_ holds: the echo first, then the reply.
void BusEngine::advance(TimePoint now) {
  if (!echo_.empty() && !rx_.empty()) {
    const std::size_t k = std::min(rx_.size(), echo_.size());
    if (!std::equal(rx_.begin(), rx_.begin() + static_cast<long>(k), echo_.begin())) {
      ++counters_.echo_errors;
      log_->debug("bus {}: echo differs from what was sent (collision?)", name_);
      tap(FrameDirection::from_drive, frame_flags::noise | frame_flags::echo, current_, rx_, now);
      echo_broken_ = true;
      echo_.clear();
      rx_.clear();
    } else {
      rx_.erase(rx_.begin(), rx_.begin() + static_cast<long>(k));
      echo_.erase(echo_.begin(), echo_.begin() + static_cast<long>(k));
    }
  }
  if (state_ == State::sending) return;  // on_sent() continues
  if (state_ == State::awaiting_echo) {
    if (echo_broken_) {
      attempt_failed(now);
    } else if (echo_.empty()) {
      after_sent(now);
    }
    return;
  }
  if (state_ == State::awaiting_reply && !rx_.empty()) process_rx(*current_, now);
}

void BusEngine::process_rx(Station& st, TimePoint now) {
  Link& link = st.link();
  while (!rx_.empty()) {
    const RxVerdict v = st.on_receive(rx_, now);
    if (v.kind == RxKind::incomplete) {
      if (rx_.size() > kMaxRxBuffer) {
        tap(FrameDirection::from_drive, frame_flags::noise, &st, rx_, now);
        link.counters.noise_bytes += static_cast<std::uint32_t>(rx_.size());
        rx_.clear();
      }
      return;
    }
    const std::size_t used = std::clamp<std::size_t>(v.consumed, 1, rx_.size());
    if (!taps_.empty()) {
      tap(FrameDirection::from_drive, verdict_flags(v.kind), &st, ByteView(rx_).first(used), now);
    }
    rx_.erase(rx_.begin(), rx_.begin() + static_cast<long>(used));
    // On a streaming line a damaged frame is usually someone else's (the stream's), so it does
    // not cost the exchange an attempt; on a request / reply line it is the reply, damaged.
    const bool awaited = state_ == State::awaiting_reply && current_ == &st;
    const bool retry_on_damage = awaited && streaming_ == nullptr;
    switch (v.kind) {
      case RxKind::reply:
      case RxKind::ack:
      case RxKind::frame: {
        ++link.counters.frames_good;
        // Only a frame carrying the drive's state makes its data fresh; an ack (a write's echo)
        // shows the drive answers, nothing more.
        const bool back = v.kind == RxKind::ack ? link.health.frame_good(now)
                                                : link.health.data_good(now, st.state_read_at(now));
        if (back) link.log->info("device {}: answering again", st.name());
        if (v.kind != RxKind::frame && awaited) {
          // Answered only after a timeout: a reply to an attempt that timed out may still come.
          if (timed_out_) start_guard(st, now);
          note_held(st, now);
          finish(now);
          return;
        }
        break;
      }
      case RxKind::nack:
      case RxKind::bad_checksum:
        ++(v.kind == RxKind::nack ? link.counters.nacks : link.counters.bad_checksum);
        if (awaited) answered_ = true;
        if (retry_on_damage) {
          attempt_failed(now);
          return;
        }
        break;
      case RxKind::foreign:
        ++link.counters.foreign;
        break;
      case RxKind::noise:
        link.counters.noise_bytes += static_cast<std::uint32_t>(used);
        break;
      case RxKind::incomplete:
        break;
    }
  }
}

}  // namespace drivegate
