#include "bus/bus.h"

#include <algorithm>

namespace drivegate {

namespace asio = boost::asio;

namespace {
constexpr Millis kFirstReopenDelay{500};
constexpr Millis kSilenceCheck{1000};
}  // namespace

Bus::Bus(asio::io_context& io, BusConfig config, std::vector<Station*> stations,
         std::shared_ptr<spdlog::logger> log)
    : config_(std::move(config)),
      log_(std::move(log)),
      engine_(config_, std::move(stations), *this, *this, log_),
      transport_(make_transport(io, config_, log_)),
      alarm_(io),
      reopen_timer_(io),
      reopen_delay_(kFirstReopenDelay),
      silence_timer_(io) {}

void Bus::start() {
  if (started_) return;
  started_ = true;
  engine_.start();
  open_port();
  if (transport_->network()) check_silence();
}

void Bus::stop() {
  stopped_ = true;
  open_ = false;
  ++alarm_generation_;
  alarm_.cancel();
  reopen_timer_.cancel();
  silence_timer_.cancel();
  transport_->close();
  engine_.stop();
}

void Bus::set_alarm(TimePoint at) {
  const std::uint64_t generation = ++alarm_generation_;
  alarm_.expires_at(at);
  alarm_.async_wait([self = shared_from_this(), generation](const boost::system::error_code& ec) {
    if (ec || generation != self->alarm_generation_ || self->stopped_) return;
    self->engine_.on_alarm();
  });
}

void Bus::send(ByteView frame) {
  transport_->write(frame, [self = shared_from_this()](std::error_code ec) {
    if (self->stopped_ || !self->open_) return;
    if (ec) {
      if (ec != std::errc::operation_canceled) self->port_failed("write: " + ec.message());
      return;
    }
    self->engine_.on_sent();
  });
}

// --- the port ---

void Bus::open_port() {
  if (stopped_ || opening_) return;
  opening_ = true;
  transport_->open([self = shared_from_this()](std::error_code ec) { self->port_opened(ec); });
}

void Bus::port_opened(std::error_code ec) {
  opening_ = false;
  if (stopped_) return;
  if (ec) {
    // Once per outage (at start-up, or after the line was lost), not at every retry.
    if (!open_failure_logged_) {
      open_failure_logged_ = true;
      log_->error("bus {}: cannot open {}: {} (retrying, at most every {} ms)", config_.name,
                  transport_->describe(), transport_->explain(ec), config_.reopen_max.count());
    }
    transport_->close();
    schedule_reopen();
    return;
  }
  // The back-off is reset only once the line gives something (read_more): a device server that
  // accepts connections but passes nothing must not be reconnected to at the fastest rate.
  open_failure_logged_ = false;
  log_->info("bus {}: {} open{}", config_.name, transport_->describe(),
             config_.network_delay.count() > 0
                 ? fmt::format(" (network_delay {} ms)", config_.network_delay.count())
                 : std::string());
  if (const std::string caveat = transport_->caveat(); !caveat.empty()) {
    log_->warn("bus {}: {}", config_.name, caveat);
  }
  open_ = true;
  last_heard_ = Clock::now();
  const bool reopened = ever_open_;
  ever_open_ = true;
  read_more();
  engine_.line_up(reopened);
}

void Bus::schedule_reopen() {
  reopen_timer_.expires_after(reopen_delay_);
  reopen_delay_ = std::min(reopen_delay_ * 2, config_.reopen_max);
  reopen_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& e) {
    if (!e) self->open_port();
  });
}

void Bus::port_failed(const std::string& what) {
  if (stopped_ || !open_) return;
  log_->warn("bus {}: {}: closing {} and reopening", config_.name, what, transport_->describe());
  open_ = false;
  transport_->close();
  engine_.line_down();
  schedule_reopen();
}

void Bus::read_more() {
  transport_->read([self = shared_from_this()](std::error_code ec, ByteView bytes) {
    if (self->stopped_ || !self->open_) return;
    if (ec) {
      if (ec != std::errc::operation_canceled) {
        self->port_failed(closed_by_peer(ec) ? std::string("the server closed the connection")
                                             : "read: " + ec.message());
      }
      return;
    }
    self->last_heard_ = Clock::now();
    self->reopen_delay_ = kFirstReopenDelay;
    self->engine_.on_received(bytes);
    if (self->open_) self->read_more();
  });
}

void Bus::check_silence() {
  silence_timer_.expires_after(kSilenceCheck);
  silence_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || self->stopped_) return;
    const auto& stations = self->engine_.stations();
    const bool all_lost =
        !stations.empty() && std::all_of(stations.begin(), stations.end(),
                                         [](Station* s) { return s->link().health.comm_lost(); });
    Millis longest{0};
    for (Station* s : stations) longest = std::max(longest, s->link().policy.comm_timeout);
    if (self->open_ && all_lost && Clock::now() - self->last_heard_ >= longest) {
      self->port_failed("every device silent for " + std::to_string(longest.count()) +
                        " ms and nothing from the server");
    }
    self->check_silence();
  });
}

}  // namespace drivegate
