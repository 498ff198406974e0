#include "transport/rfc2217_transport.h"

#include <spdlog/spdlog.h>

#include <boost/asio/post.hpp>

namespace drivegate {

namespace asio = boost::asio;
using namespace telnet;

namespace {
// How long a server has to agree to COM-PORT-OPTION and answer the settings.
constexpr std::chrono::seconds kNegotiationLimit{5};

enum class Failure { refused = 1, settings_differ, no_answer };

class Category final : public std::error_category {
 public:
  const char* name() const noexcept override { return "rfc2217"; }
  std::string message(int v) const override {
    switch (static_cast<Failure>(v)) {
      case Failure::refused:
        return "the server refuses COM-PORT-OPTION (is the port set up for RFC 2217?)";
      case Failure::settings_differ:
        return "the server did not take the line settings";
      case Failure::no_answer:
        return "the server did not answer the line settings within 5 s (is the port set up "
               "for RFC 2217, not raw TCP?)";
    }
    return "rfc2217 error";
  }
};

std::error_code make_error(Failure f) {
  static const Category category;
  return {static_cast<int>(f), category};
}
}  // namespace

Rfc2217Transport::Rfc2217Transport(asio::io_context& io, const BusConfig& bus, std::string host,
                                   std::uint16_t port, std::shared_ptr<spdlog::logger> log)
    : bus_(bus.name),
      log_(std::move(log)),
      tcp_(io, std::move(host), port),
      asked_{bus.baud, bus.data_bits, bus.parity, bus.stop_bits},
      open_timer_(io) {}

void Rfc2217Transport::open(Done done) {
  decoder_ = {};
  answered_ = {};
  com_port_agreed_ = false;
  queue_.clear();
  writing_ = false;
  // Shared with the handlers below, so what `done` holds (the bus) lives until they ran.
  opening_ = std::make_shared<Done>(std::move(done));
  const std::uint64_t generation = generation_;
  tcp_.open([this, generation, keep = opening_](std::error_code ec) {
    if (generation != generation_) return;
    if (ec) {
      finish_open(ec);
      return;
    }
    open_timer_.expires_after(kNegotiationLimit);
    open_timer_.async_wait([this, generation, keep](const boost::system::error_code& e) {
      if (e || generation != generation_ || !opening_) return;
      finish_open(make_error(Failure::no_answer));
    });
    // RFC 2217 section "Basic Concepts": the client asks to send COM-PORT-OPTION commands
    // (WILL); binary mode both ways so CR and NUL pass untouched (RFC 856).
    Bytes hello;
    for (const Bytes& b : {negotiation(kWill, kBinary), negotiation(kDo, kBinary),
                           negotiation(kWill, kSuppressGoAhead), negotiation(kDo, kSuppressGoAhead),
                           negotiation(kWill, kComPortOption)}) {
      hello.insert(hello.end(), b.begin(), b.end());
    }
    send_raw(std::move(hello), [](std::error_code) {});
    negotiate_more();
  });
}

// While opening, reads are ours: negotiation and the answers to the settings.
void Rfc2217Transport::negotiate_more() {
  const std::uint64_t generation = generation_;
  tcp_.read([this, generation, keep = opening_](std::error_code ec, ByteView raw) {
    if (generation != generation_ || !opening_) return;
    if (ec) {
      finish_open(ec);
      return;
    }
    on_bytes(raw);  // data before the line is open is dropped: nothing was asked yet
    if (!opening_) return;
    if (answered_.complete()) {
      const std::string differs = rfc2217::mismatch(asked_, answered_);
      if (!differs.empty())
        log_->error("bus {}: {}: the server answered {}", bus_, describe(), differs);
      finish_open(differs.empty() ? std::error_code{} : make_error(Failure::settings_differ));
      return;
    }
    negotiate_more();
  });
}

void Rfc2217Transport::on_bytes(ByteView raw) {
  data_.clear();
  events_.clear();
  decoder_.feed(raw, data_, events_);
  for (const Event& e : events_) answer(e);
}

void Rfc2217Transport::answer(const Event& e) {
  if (e.kind == Event::Kind::subnegotiation) {
    if (e.option == kComPortOption) rfc2217::take_answer(e.payload, answered_);
    return;
  }
  const bool ours =
      e.option == kBinary || e.option == kSuppressGoAhead || e.option == kComPortOption;
  switch (e.verb) {
    case kDo:  // the server agrees to our WILL, or asks us to
      if (e.option == kComPortOption && !com_port_agreed_) {
        com_port_agreed_ = true;
        send_raw(rfc2217::configure(asked_), [](std::error_code) {});
      } else if (!ours) {
        send_raw(negotiation(kWont, e.option), [](std::error_code) {});
      }
      break;
    case kDont:
      if (e.option == kComPortOption && opening_) finish_open(make_error(Failure::refused));
      break;
    case kWill:
      if (!ours) send_raw(negotiation(kDont, e.option), [](std::error_code) {});
      break;
    default:  // WONT: nothing to answer
      break;
  }
}

void Rfc2217Transport::finish_open(std::error_code ec) {
  open_timer_.cancel();
  if (!opening_) return;
  const auto done = std::move(opening_);
  opening_.reset();
  (*done)(ec);
}

void Rfc2217Transport::read(Received received) {
  const std::uint64_t generation = generation_;
  tcp_.read(
      [this, generation, received = std::move(received)](std::error_code ec, ByteView raw) mutable {
        if (generation != generation_) return;
        if (ec) {
          received(ec, {});
          return;
        }
        on_bytes(raw);
        if (data_.empty()) {  // only Telnet commands in this chunk: wait for data
          read(std::move(received));
          return;
        }
        received(ec, data_);
      });
}

void Rfc2217Transport::write(ByteView data, Done done) {
  Bytes escaped;
  escaped.reserve(data.size() + 4);
  escape(data, escaped);
  send_raw(std::move(escaped), std::move(done));
}

void Rfc2217Transport::send_raw(Bytes bytes, Done done) {
  queue_.emplace_back(std::move(bytes), std::move(done));
  if (!writing_) send_next();
}

void Rfc2217Transport::send_next() {
  if (queue_.empty()) {
    writing_ = false;
    return;
  }
  writing_ = true;
  auto [bytes, done] = std::move(queue_.front());
  queue_.pop_front();
  const std::uint64_t generation = generation_;
  tcp_.write_raw(std::move(bytes), [this, generation, done = std::move(done)](std::error_code ec) {
    if (generation != generation_) return;
    done(ec);
    if (ec) {
      writing_ = false;
      return;
    }
    send_next();
  });
}

void Rfc2217Transport::close() {
  ++generation_;
  open_timer_.cancel();
  opening_.reset();
  queue_.clear();
  writing_ = false;
  tcp_.close();
}

std::string Rfc2217Transport::describe() const {
  const char* parity = asked_.parity == Parity::none   ? "N"
                       : asked_.parity == Parity::even ? "E"
                                                       : "O";
  return "rfc2217 " + tcp_.endpoint() + " (set to " + std::to_string(asked_.baud) + " " +
         std::to_string(asked_.data_bits) + parity + std::to_string(asked_.stop_bits) + ")";
}

}  // namespace drivegate
