#include "bus.h"

#include <spdlog/fmt/bin_to_hex.h>

#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>

#include "serial_line.h"

namespace drivegate {

namespace asio = boost::asio;

namespace {
// A reply buffer that grows past this without a frame is line garbage, not a frame in progress.
constexpr std::size_t kMaxRxBuffer = 4096;
constexpr Millis kFirstReopenDelay{500};
}  // namespace

Bus::Bus(asio::io_context& io, BusConfig config, std::vector<Device*> devices,
         std::shared_ptr<spdlog::logger> log)
    : io_(io),
      config_(std::move(config)),
      devices_(std::move(devices)),
      log_(std::move(log)),
      port_(io),
      timer_(io),
      reopen_timer_(io),
      reopen_delay_(kFirstReopenDelay),
      char_time_(char_time(config_)) {
  for (Device* d : devices_) {
    if (d->adapter().streaming) streaming_ = d;
    d->attach_bus(&counters_);
  }
}

void Bus::start() {
  if (started_) return;
  started_ = true;
  std::weak_ptr<Bus> weak = weak_from_this();
  for (Device* d : devices_) {
    d->on_work([weak] {
      if (auto self = weak.lock()) self->kick();
    });
  }
  open_port();
}

void Bus::stop() {
  stopped_ = true;
  ++timer_generation_;
  timer_.cancel();
  reopen_timer_.cancel();
  boost::system::error_code ignored;
  port_.close(ignored);
  state_ = State::closed;
  exchange_.reset();
  current_ = nullptr;
  for (Device* d : devices_) d->on_work(nullptr);
}

void Bus::kick() {
  asio::post(io_, [self = shared_from_this()] { self->pump(); });
}

// --- the port ---

void Bus::open_port() {
  if (stopped_) return;
  if (const std::error_code ec = open_serial(port_, config_)) {
    if (reopen_delay_ == kFirstReopenDelay) {
      log_->error("bus {}: cannot open {}: {} (retrying, at most every {} ms)", config_.name,
                  config_.port, ec.message(), config_.reopen_max.count());
    }
    reopen_timer_.expires_after(reopen_delay_);
    reopen_delay_ = std::min(reopen_delay_ * 2, config_.reopen_max);
    reopen_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& e) {
      if (!e) self->open_port();
    });
    return;
  }
  if (reopen_delay_ != kFirstReopenDelay) ++counters_.reopens;
  reopen_delay_ = kFirstReopenDelay;
  log_->info("bus {}: {} open ({} baud, {} data, {} parity, {} stop{}{})", config_.name,
             config_.port, config_.baud, config_.data_bits,
             config_.parity == Parity::none   ? "no"
             : config_.parity == Parity::even ? "even"
                                              : "odd",
             config_.stop_bits, config_.echo ? ", echo" : "", config_.rs485 ? ", RS-485" : "");
  state_ = State::idle;
  rx_.clear();
  last_activity_ = Clock::now();
  read_more();
  pump();
}

void Bus::port_failed(const std::string& what) {
  if (stopped_ || state_ == State::closed) return;
  log_->warn("bus {}: {}: closing {} and reopening", config_.name, what, config_.port);
  boost::system::error_code ignored;
  port_.close(ignored);
  ++timer_generation_;
  const auto now = Clock::now();
  if (Device* dev = current_; dev != nullptr) {
    exchange_.reset();
    current_ = nullptr;
    dev->driver().on_no_reply(now);
    dev->turn_failed(now);
    dev->sync(now);
  }
  state_ = State::closed;
  reopen_timer_.expires_after(reopen_delay_);
  reopen_delay_ = std::min(reopen_delay_ * 2, config_.reopen_max);
  reopen_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& e) {
    if (!e) self->open_port();
  });
}

void Bus::read_more() {
  port_.async_read_some(
      asio::buffer(chunk_),
      [self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
        if (ec) {
          if (ec != asio::error::operation_aborted) self->port_failed("read: " + ec.message());
          return;
        }
        self->on_bytes(n);
        if (self->state_ != State::closed) self->read_more();
      });
}

// --- receiving ---

void Bus::on_bytes(std::size_t n) {
  const auto now = Clock::now();
  last_activity_ = now;
  log_->trace("bus {}: rx {:n}", config_.name, spdlog::to_hex(chunk_.begin(), chunk_.begin() + n));
  const bool in_exchange =
      exchange_ && (state_ == State::writing || state_ == State::awaiting_echo ||
                    state_ == State::awaiting_reply);
  if (!in_exchange && streaming_ == nullptr) {
    counters_.noise_bytes += static_cast<std::uint32_t>(n);  // a late reply or line noise
    return;
  }
  rx_.insert(rx_.end(), chunk_.begin(), chunk_.begin() + static_cast<long>(n));
  if (in_exchange) {
    advance();
  } else {
    process_rx(*streaming_);
  }
}

// Moves an exchange forward with what rx_ holds: the echo first, then the reply.
void Bus::advance() {
  if (!echo_.empty() && !rx_.empty()) {
    const std::size_t k = std::min(rx_.size(), echo_.size());
    if (!std::equal(rx_.begin(), rx_.begin() + static_cast<long>(k), echo_.begin())) {
      ++counters_.echo_errors;
      log_->debug("bus {}: echo differs from what was sent (collision?)", config_.name);
      echo_broken_ = true;
      echo_.clear();
      rx_.clear();
    } else {
      rx_.erase(rx_.begin(), rx_.begin() + static_cast<long>(k));
      echo_.erase(echo_.begin(), echo_.begin() + static_cast<long>(k));
    }
  }
  if (state_ == State::writing) return;  // the write handler continues
  if (state_ == State::awaiting_echo) {
    if (echo_broken_) {
      attempt_failed();
      return;
    }
    if (!echo_.empty()) return;
    after_sent();
    return;
  }
  if (state_ == State::awaiting_reply && !rx_.empty()) process_rx(*current_);
}

void Bus::process_rx(Device& dev) {
  const auto now = Clock::now();
  while (!rx_.empty()) {
    const RxVerdict v = dev.driver().on_receive(rx_, now);
    if (v.kind == RxKind::incomplete) {
      if (rx_.size() > kMaxRxBuffer) {
        dev.counters().noise_bytes += static_cast<std::uint32_t>(rx_.size());
        rx_.clear();
      }
      break;
    }
    const std::size_t used = std::clamp<std::size_t>(v.consumed, 1, rx_.size());
    rx_.erase(rx_.begin(), rx_.begin() + static_cast<long>(used));
    // On a streaming line a damaged frame is usually someone else's (the stream's), so it does
    // not cost the exchange an attempt; on a request / reply line it is the reply, damaged.
    const bool awaited = state_ == State::awaiting_reply && current_ == &dev;
    const bool retry_on_damage = awaited && streaming_ == nullptr;
    switch (v.kind) {
      case RxKind::reply:
        dev.frame_good(now);
        if (awaited) {
          dev.sync(now);
          finish();
          return;
        }
        break;
      case RxKind::frame:
        dev.frame_good(now);
        break;
      case RxKind::nack:
        ++dev.counters().nacks;
        if (awaited) answered_ = true;
        if (retry_on_damage) {
          dev.sync(now);
          attempt_failed();
          return;
        }
        break;
      case RxKind::bad_checksum:
        ++dev.counters().bad_checksum;
        if (awaited) answered_ = true;
        if (retry_on_damage) {
          dev.sync(now);
          attempt_failed();
          return;
        }
        break;
      case RxKind::foreign:
        ++dev.counters().foreign;
        break;
      case RxKind::noise:
        dev.counters().noise_bytes += static_cast<std::uint32_t>(used);
        break;
      case RxKind::incomplete:
        break;
    }
  }
  dev.sync(now);
}

// --- transmitting ---

void Bus::pump() {
  if (state_ != State::idle || stopped_ || devices_.empty()) return;
  const auto now = Clock::now();
  const std::size_t n = devices_.size();
  // Writes first, then polls, each round-robin from where the last turn ended.
  for (int pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t idx = (next_device_ + i) % n;
      Device& d = *devices_[idx];
      const bool writes = d.has_pending_writes();
      if (pass == 0 && !writes) continue;
      if (pass == 1 && (writes || d.in_backoff(now) || d.driver().wake_at() > now)) continue;
      std::optional<Exchange> ex = d.driver().next_exchange(now);
      d.sync(now);
      if (ex) {
        next_device_ = (idx + 1) % n;
        begin(d, std::move(*ex));
        return;
      }
    }
  }
  // Nothing due: sleep until the earliest device wants the line (a kick wakes us sooner).
  TimePoint wake = now + std::chrono::seconds(1);
  for (Device* d : devices_) {
    const TimePoint w = d->in_backoff(now) ? d->probe_at() : d->driver().wake_at();
    wake = std::min(wake, std::max(w, now + Millis(1)));
  }
  arm(wake - now, &Bus::pump);
}

void Bus::begin(Device& dev, Exchange ex) {
  current_ = &dev;
  exchange_ = std::move(ex);
  attempt_ = 0;
  // The device's time budget caps how many attempts one turn may take.
  const auto on_wire = char_time_ * static_cast<long>(exchange_->frame.size());
  const auto per_attempt =
      std::chrono::duration_cast<Millis>(exchange_->timeout + on_wire * (config_.echo ? 2 : 1)) +
      Millis(1);
  const auto fit = static_cast<int>(dev.config().budget / per_attempt);
  max_attempts_ = std::clamp(fit, 1, std::max<int>(1, exchange_->attempts));
  answered_ = false;
  ++counters_.exchanges;
  send_attempt();
}

void Bus::send_attempt() {
  const auto now = Clock::now();
  const auto since = now - last_activity_;
  const auto gap = current_->traits().inter_frame_gap;
  if (since < gap) {
    state_ = State::gap;
    arm(gap - since, &Bus::send_attempt);
    return;
  }
  state_ = State::writing;
  tx_ = exchange_->frame;
  echo_ = config_.echo ? tx_ : Bytes{};
  echo_broken_ = false;
  if (streaming_ == nullptr) rx_.clear();
  log_->trace("bus {}: tx {:n}", config_.name, spdlog::to_hex(tx_));
  asio::async_write(port_, asio::buffer(tx_),
                    [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
                      if (ec) {
                        if (ec != asio::error::operation_aborted) {
                          self->port_failed("write: " + ec.message());
                        }
                        return;
                      }
                      self->on_written();
                    });
}

void Bus::on_written() {
  if (state_ != State::writing) return;
  last_activity_ = Clock::now();
  if (config_.echo) {
    // The echo is back once the frame has crossed the wire; allow that time and a little more.
    state_ = State::awaiting_echo;
    arm(char_time_ * static_cast<long>(tx_.size() + 2) + Millis(50), &Bus::on_reply_timeout);
    advance();
    return;
  }
  after_sent();
}

void Bus::after_sent() {
  if (exchange_->reply == ReplyMode::none) {
    finish();
    return;
  }
  state_ = State::awaiting_reply;
  // The write completes when the kernel has the bytes, not when they have left the UART.
  const auto on_wire =
      config_.echo ? std::chrono::microseconds(0) : char_time_ * static_cast<long>(tx_.size());
  arm(exchange_->timeout + on_wire, &Bus::on_reply_timeout);
  if (!rx_.empty()) process_rx(*current_);
}

void Bus::on_reply_timeout() {
  if (state_ == State::awaiting_reply) {
    ++counters_.timeouts;
    ++current_->counters().timeouts;
    log_->debug("bus {}: device {} did not answer (attempt {} of {})", config_.name,
                current_->config().name, attempt_ + 1, max_attempts_);
  } else if (state_ == State::awaiting_echo) {
    ++counters_.echo_errors;
    log_->debug("bus {}: our own frame did not come back (one-wire line broken?)", config_.name);
  } else {
    return;
  }
  attempt_failed();
}

void Bus::attempt_failed() {
  ++timer_generation_;
  if (++attempt_ < max_attempts_) {
    ++counters_.retries;
    ++current_->counters().retries;
    send_attempt();
    return;
  }
  Device* dev = current_;
  const auto now = Clock::now();
  exchange_.reset();
  current_ = nullptr;
  state_ = State::idle;
  echo_.clear();
  dev->driver().on_no_reply(now);
  // A device that NACKs or answers garbled is there: keep its poll rate, back off only silence.
  if (!answered_) dev->turn_failed(now);
  dev->sync(now);
  pump();
}

void Bus::finish() {
  ++timer_generation_;
  exchange_.reset();
  current_ = nullptr;
  state_ = State::idle;
  echo_.clear();
  pump();
}

void Bus::arm(std::chrono::steady_clock::duration after, void (Bus::*handler)()) {
  const std::uint64_t generation = ++timer_generation_;
  timer_.expires_after(after);
  timer_.async_wait(
      [self = shared_from_this(), generation, handler](const boost::system::error_code& ec) {
        if (ec || generation != self->timer_generation_ || self->stopped_) return;
        ((*self).*handler)();
      });
}

}  // namespace drivegate
