#include "line/bus.h"

#include <boost/asio/write.hpp>

#include "line/serial_line.h"

namespace drivegate {

namespace asio = boost::asio;

namespace {
constexpr Millis kFirstReopenDelay{500};

const char* parity_name(Parity p) {
  switch (p) {
    case Parity::none:
      return "no";
    case Parity::even:
      return "even";
    case Parity::odd:
      return "odd";
  }
  return "?";
}
}  // namespace

Bus::Bus(asio::io_context& io, BusConfig config, std::vector<Station*> stations,
         std::shared_ptr<spdlog::logger> log)
    : io_(io),
      config_(std::move(config)),
      log_(std::move(log)),
      engine_(config_, std::move(stations), *this, *this, log_),
      port_(io),
      alarm_(io),
      reopen_timer_(io),
      reopen_delay_(kFirstReopenDelay) {}

void Bus::start() {
  if (started_) return;
  started_ = true;
  engine_.start();
  open_port();
}

void Bus::stop() {
  stopped_ = true;
  open_ = false;
  ++alarm_generation_;
  alarm_.cancel();
  reopen_timer_.cancel();
  boost::system::error_code ignored;
  port_.close(ignored);
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
  tx_.assign(frame.begin(), frame.end());
  asio::async_write(port_, asio::buffer(tx_),
                    [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
                      if (self->stopped_) return;
                      if (ec) {
                        if (ec != asio::error::operation_aborted) {
                          self->port_failed("write: " + ec.message());
                        }
                        return;
                      }
                      self->engine_.on_sent();
                    });
}

// --- the port ---

void Bus::open_port() {
  if (stopped_) return;
  if (const std::error_code ec = open_serial(port_, config_)) {
    if (reopen_delay_ == kFirstReopenDelay) {
      log_->error("bus {}: cannot open {}: {} (retrying, at most every {} ms)", config_.name,
                  config_.port, ec.message(), config_.reopen_max.count());
    }
    schedule_reopen();
    return;
  }
  reopen_delay_ = kFirstReopenDelay;
  log_->info("bus {}: {} open ({} baud, {} data, {} parity, {} stop{}{})", config_.name,
             config_.port, config_.baud, config_.data_bits, parity_name(config_.parity),
             config_.stop_bits, config_.echo ? ", echo" : "", config_.rs485 ? ", RS-485" : "");
  open_ = true;
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
  log_->warn("bus {}: {}: closing {} and reopening", config_.name, what, config_.port);
  open_ = false;
  boost::system::error_code ignored;
  port_.close(ignored);
  engine_.line_down();
  schedule_reopen();
}

void Bus::read_more() {
  port_.async_read_some(
      asio::buffer(chunk_),
      [self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
        if (self->stopped_) return;
        if (ec) {
          if (ec != asio::error::operation_aborted) self->port_failed("read: " + ec.message());
          return;
        }
        self->engine_.on_received(ByteView(self->chunk_.data(), n));
        if (self->open_) self->read_more();
      });
}

}  // namespace drivegate
