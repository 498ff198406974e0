#include "serial_listener.h"

#include <algorithm>

namespace drivegate::slave {

namespace {

constexpr std::chrono::milliseconds kFirstRetry{100};

std::string framing_name(modbus_serial::Framing f) {
  return f == modbus_serial::Framing::rtu ? "rtu" : "ascii";
}

modbus::LineTiming timing_of(const SerialListenerOptions& o) {
  // A character: start bit, data bits, parity bit if any, stop bits (Serial Line 2.5.1).
  const unsigned bits =
      1U + o.line.data_bits + (o.line.parity == Parity::none ? 0U : 1U) + o.line.stop_bits;
  auto t = modbus::line_timing(o.line.baud, bits);
  t.ascii_timeout = o.ascii_timeout;
  t.latency = o.latency;
  return t;
}

}  // namespace

SerialListener::SerialListener(boost::asio::io_context& io, net::Clock& clock,
                               modbus::Backend& backend, SerialListenerOptions options,
                               std::shared_ptr<const SlavePolicy> policy,
                               std::shared_ptr<spdlog::logger> log)
    : options_(std::move(options)),
      policy_(std::move(policy)),
      log_(std::move(log)),
      name_("serial " + options_.line.port + " (" + framing_name(options_.framing) + ")"),
      transport_(make_transport(io, options_.line, log_)),
      retry_(io.get_executor(), clock) {
  // The host lives only as long as this listener (host_ is its one owner).
  auto send = [this](Bytes frame) { this->send(std::move(frame)); };
  const auto delimit =
      options_.line.port.starts_with("tcp://") ? modbus::Delimit::length : modbus::Delimit::silence;
  host_ =
      std::make_shared<SlaveHost>(io, clock, backend, options_.identity, options_.framing, delimit,
                                  timing_of(options_), policy_, counters_, log_, name_, send);
}

SerialListener::~SerialListener() {
  close();
}

void SerialListener::start() {
  log_->info("modbus: {}: {}, access {}, {} word order, writes answered when {}{}", name_,
             transport_->describe(), to_string(policy_->session.access),
             to_string(policy_->session.word_order),
             policy_->write_reply == WriteReply::confirmed ? "the drive took them"
                                                           : "validated and queued",
             policy_->broadcast ? ", broadcast writes applied" : "");
  try_open();
}

void SerialListener::close() {
  if (closed_) return;
  closed_ = true;
  *alive_ = false;
  alive_ = std::make_shared<bool>(false);
  retry_.cancel();
  host_->stop();
  transport_->close();
  open_ = false;
}

void SerialListener::set_policy(std::shared_ptr<const SlavePolicy> policy) {
  policy_ = std::move(policy);
  host_->set_policy(policy_);
}

void SerialListener::try_open() {
  if (closed_) return;
  transport_->open([this, alive = std::weak_ptr<bool>(alive_)](std::error_code ec) {
    if (auto a = alive.lock(); a && *a) on_open(ec);
  });
}

void SerialListener::on_open(std::error_code ec) {
  if (ec) {
    if (!outage_logged_) {
      outage_logged_ = true;
      log_->error("modbus: {}: cannot open {}: {}; retrying (logged once until it opens)", name_,
                  transport_->describe(), transport_->explain(ec));
    }
    retry_later();
    return;
  }
  open_ = true;
  backoff_ = kFirstRetry;
  if (outage_logged_ || reopens_ > 0) {
    log_->info("modbus: {}: {} open again", name_, transport_->describe());
  } else {
    log_->info("modbus: {}: {} open", name_, transport_->describe());
  }
  if (auto caveat = transport_->caveat(); !caveat.empty()) {
    log_->warn("modbus: {}: {}", name_, caveat);
  }
  outage_logged_ = false;
  read();
}

void SerialListener::read() {
  transport_->read([this, alive = std::weak_ptr<bool>(alive_)](std::error_code ec, ByteView data) {
    if (auto a = alive.lock(); a && *a) on_read(ec, data);
  });
}

void SerialListener::on_read(std::error_code ec, ByteView data) {
  if (ec) {
    lost(ec, "read");
    return;
  }
  bytes_received_ += data.size();
  // Our own reply coming back on an echoing line is not the master speaking.
  std::size_t own = 0;
  while (own < data.size() && !echo_.empty() && data[own] == echo_.front()) {
    echo_.erase(echo_.begin());
    ++own;
  }
  if (own < data.size()) echo_.clear();  // anything else: the echo is over, or was garbled
  host_->receive(data.subspan(own));
  if (!closed_ && open_) read();
}

void SerialListener::send(Bytes frame) {
  if (!open_) return;
  if (options_.line.echo) echo_.insert(echo_.end(), frame.begin(), frame.end());
  if (writing_) {
    tx_queue_.insert(tx_queue_.end(), frame.begin(), frame.end());
    return;
  }
  writing_ = true;
  transport_->write(frame, [this, alive = std::weak_ptr<bool>(alive_)](std::error_code ec) {
    auto a = alive.lock();
    if (!a || !*a) return;
    writing_ = false;
    if (ec) {
      lost(ec, "write");
      return;
    }
    if (!tx_queue_.empty()) {
      Bytes next = std::move(tx_queue_);
      tx_queue_.clear();
      send(std::move(next));
    }
  });
}

// The port went (an adapter unplugged, a device server gone): closed, the host told (a write in
// progress is left to settle unanswered), and reopened with back-off.
void SerialListener::lost(std::error_code ec, const char* what) {
  if (closed_ || !open_) return;
  open_ = false;
  writing_ = false;
  tx_queue_.clear();
  echo_.clear();
  host_->reset();
  transport_->close();
  // Callbacks of the closed port (operation_aborted) must not reach the reopened one.
  *alive_ = false;
  alive_ = std::make_shared<bool>(true);
  if (!outage_logged_) {
    outage_logged_ = true;
    log_->error("modbus: {}: {} failed: {}; reopening (logged once until it is back)", name_, what,
                transport_->explain(ec));
  }
  ++reopens_;
  retry_later();
}

void SerialListener::retry_later() {
  retry_.expires_after(backoff_);
  backoff_ = std::min<std::chrono::milliseconds>(backoff_ * 2, options_.line.reopen_max);
  retry_.async_wait(
      [this, alive = std::weak_ptr<bool>(alive_)](const boost::system::error_code& e) {
        if (auto a = alive.lock(); a && *a && !e) try_open();
      });
}

}  // namespace drivegate::slave
