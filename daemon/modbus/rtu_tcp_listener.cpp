#include "rtu_tcp_listener.h"

#include <boost/asio/write.hpp>

namespace drivegate::slave {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {

// Replies not yet taken by a client that does not read them: past this much, the connection
// stops reading its requests until it does (as the Modbus TCP connection does), so a client that
// never reads cannot make the daemon hold its answers without bound.
constexpr std::size_t kMaxReplyBacklog = 64 * 1024;

}  // namespace

// One client: its socket, its host, what it has yet to be sent.
class RtuTcpListener::Client : public std::enable_shared_from_this<Client> {
 public:
  Client(RtuTcpListener& listener, tcp::socket socket, asio::ip::address address, std::string peer)
      : listener_(listener.weak_from_this()),
        socket_(std::move(socket)),
        address_(std::move(address)),
        peer_(std::move(peer)),
        idle_(socket_.get_executor(), listener.clock_),
        idle_timeout_(listener.options_.idle_timeout),
        frame_timeout_(listener.options_.frame_timeout),
        clock_(listener.clock_) {
    host_ = std::make_shared<SlaveHost>(
        listener.io_, listener.clock_, listener.backend_, listener.options_.identity,
        listener.options_.framing, modbus::Delimit::length, modbus::LineTiming{},
        listener.client_policy(peer_), listener.counters_, listener.log_,
        listener.name_ + " client " + peer_, [this](Bytes frame) { send(std::move(frame)); });
    host_->when_settled([this] { close_if_done(); });
  }

  void start() {
    last_request_ = clock_.now();
    arm_idle();
    read();
  }
  void close() {
    if (closed_) return;
    closed_ = true;
    host_->stop();
    idle_.cancel();
    boost::system::error_code ignored;
    socket_.shutdown(tcp::socket::shutdown_both, ignored);
    socket_.close(ignored);
  }
  void set_policy(std::shared_ptr<const SlavePolicy> p) { host_->set_policy(std::move(p)); }
  [[nodiscard]] const std::string& peer() const { return peer_; }
  [[nodiscard]] const asio::ip::address& address() const { return address_; }
  // Closed by the listener (a reload took its address off the allow list).
  void drop() { gone(); }

 private:
  void read() {
    if (input_done_) return;
    socket_.async_read_some(asio::buffer(rx_),
                            [self = shared_from_this()](const boost::system::error_code& ec,
                                                        std::size_t n) { self->on_read(ec, n); });
  }
  void on_read(const boost::system::error_code& ec, std::size_t n) {
    if (closed_) return;
    // The client is done sending (shutdown SHUT_WR): every request it sent is still carried out
    // and answered, as on the Modbus TCP listener (modbus/connection.h); then the close. A frame
    // left half-sent will never be finished.
    if (ec == asio::error::eof) {
      input_done_ = true;
      close_if_done();
      return;
    }
    if (ec) {  // reset: a write in progress settles unanswered
      gone();
      return;
    }
    const auto now = clock_.now();
    last_request_ = now;
    if (auto l = listener_.lock()) l->bytes_received_ += n;
    host_->receive(ByteView(rx_.data(), n));
    if (!host_->partial()) {
      partial_since_.reset();
    } else if (!partial_since_) {
      partial_since_ = now;
      arm_idle();
    }
    if (closed_) return;
    if (tx_.size() + inflight_.size() > kMaxReplyBacklog) {
      paused_ = true;  // flush() reads again once the client has taken its replies
      return;
    }
    read();
  }
  void send(Bytes frame) {
    if (closed_) return;
    tx_.insert(tx_.end(), frame.begin(), frame.end());
    flush();
  }
  void flush() {
    if (writing_ || tx_.empty() || closed_) return;
    writing_ = true;
    inflight_ = std::move(tx_);
    tx_.clear();
    asio::async_write(
        socket_, asio::buffer(inflight_),
        [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
          self->writing_ = false;
          if (ec) {
            self->gone();
            return;
          }
          self->flush();
          self->close_if_done();
          if (self->paused_ && !self->closed_ &&
              self->tx_.size() + self->inflight_.size() <= kMaxReplyBacklog / 2) {
            self->paused_ = false;
            self->read();
          }
        });
  }
  // Half-closed, with nothing left to answer or to send: closed.
  void close_if_done() {
    if (input_done_ && !closed_ && !host_->busy() && !writing_ && tx_.empty()) gone();
  }
  // The next deadline: idle (no request for idle_timeout), or a partial frame left unfinished
  // for frame_timeout (a client holding a slot with one byte a minute).
  [[nodiscard]] std::optional<net::TimePoint> deadline() const {
    std::optional<net::TimePoint> at;
    if (idle_timeout_.count() > 0) at = last_request_ + idle_timeout_;
    if (partial_since_ && frame_timeout_.count() > 0) {
      const auto f = *partial_since_ + frame_timeout_;
      if (!at || f < *at) at = f;
    }
    return at;
  }
  void arm_idle() {
    const auto at = deadline();
    if (!at) return;
    idle_.expires_at(*at);
    idle_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec || self->closed_) return;
      const auto now = self->clock_.now();
      const bool stale = self->partial_since_ && self->frame_timeout_.count() > 0 &&
                         now >= *self->partial_since_ + self->frame_timeout_;
      const bool idle = self->idle_timeout_.count() > 0 &&
                        now >= self->last_request_ + self->idle_timeout_ && !self->host_->busy();
      if (stale || idle) {
        self->gone();
        return;
      }
      self->arm_idle();
    });
  }
  void gone() {
    if (closed_) return;
    close();
    if (auto l = listener_.lock()) {
      l->acceptor_->left();
      l->clients_.erase(shared_from_this());
    }
  }

  std::weak_ptr<RtuTcpListener> listener_;
  tcp::socket socket_;
  asio::ip::address address_;
  std::string peer_;
  net::Timer idle_;
  std::chrono::milliseconds idle_timeout_;
  std::chrono::milliseconds frame_timeout_;
  std::optional<net::TimePoint> partial_since_;
  bool paused_ = false;  // not reading: too many replies the client has not taken
  net::Clock& clock_;
  std::shared_ptr<SlaveHost> host_;
  std::array<std::uint8_t, 512> rx_{};
  Bytes tx_;
  Bytes inflight_;
  net::TimePoint last_request_{};
  bool writing_ = false;
  bool input_done_ = false;  // the client half-closed: answer what it sent, then close
  bool closed_ = false;
};

RtuTcpListener::RtuTcpListener(asio::io_context& io, net::Clock& clock, modbus::Backend& backend,
                               RtuTcpOptions options, std::shared_ptr<const SlavePolicy> policy,
                               std::shared_ptr<spdlog::logger> log)
    : io_(io),
      clock_(clock),
      backend_(backend),
      options_(std::move(options)),
      policy_(std::move(policy)),
      log_(std::move(log)),
      name_((options_.host.find(':') != std::string::npos ? "[" + options_.host + "]"
                                                          : options_.host) +
            ":" + std::to_string(options_.port) +
            (options_.framing == modbus_serial::Framing::rtu ? " (rtu over tcp)"
                                                             : " (ascii over tcp)")),
      acceptor_(
          std::make_shared<net::Acceptor>(io, clock, log_, "modbus: " + name_, options_.allow)) {}

RtuTcpListener::~RtuTcpListener() {
  close();
}

std::shared_ptr<const SlavePolicy> RtuTcpListener::client_policy(const std::string& peer) const {
  auto p = std::make_shared<SlavePolicy>(*policy_);
  p->session.source.client = peer;
  return p;
}

std::error_code RtuTcpListener::listen() {
  if (auto ec = acceptor_->bind(options_.host, options_.port, 128, net::AnyAddress::dual_stack)) {
    log_->error("modbus: cannot listen on {}: {}", name_, ec.message());
    return ec;
  }
  const auto session = policy_->session;
  log_->info("modbus: listening on {}: access {}, {} word order, writes answered when {}{}", name_,
             to_string(session.access), to_string(session.word_order),
             policy_->write_reply == WriteReply::confirmed ? "the drive took them"
                                                           : "validated and queued",
             policy_->broadcast ? ", broadcast writes applied" : "");
  acceptor_->start(
      [weak = weak_from_this()](const asio::ip::address&) {
        auto self = weak.lock();
        if (!self || self->clients_.size() >= self->options_.max_clients) {
          return net::Admission::refuse;
        }
        return net::Admission::take;
      },
      [weak = weak_from_this()](tcp::socket socket) {
        auto self = weak.lock();
        if (!self) return;
        boost::system::error_code ec;
        const auto ep = socket.remote_endpoint(ec);
        std::string peer = ec ? std::string("?")
                              : (ep.address().is_v6() ? "[" + ep.address().to_string() + "]"
                                                      : ep.address().to_string()) +
                                    ":" + std::to_string(ep.port());
        socket.set_option(tcp::no_delay(true), ec);
        auto c = std::make_shared<Client>(*self, std::move(socket), ep.address(), std::move(peer));
        self->clients_.insert(c);
        c->start();
      });
  return {};
}

void RtuTcpListener::close() {
  if (closed_) return;
  closed_ = true;
  acceptor_->close();
  const auto open = clients_;
  clients_.clear();
  for (const auto& c : open) c->close();
}

void RtuTcpListener::set_policy(std::shared_ptr<const SlavePolicy> policy, net::AllowList allow,
                                std::size_t max_clients) {
  policy_ = std::move(policy);
  options_.max_clients = max_clients;
  options_.allow = allow;
  acceptor_->set_allow(std::move(allow));
  const auto open = clients_;
  for (const auto& c : open) {
    if (!net::allowed(options_.allow, c->address())) {
      log_->warn("modbus: {}: client {} closed: its address is no longer allowed", name_,
                 c->peer());
      c->drop();
      continue;
    }
    c->set_policy(client_policy(c->peer()));
  }
}

std::uint16_t RtuTcpListener::port() const {
  return acceptor_->local_endpoint().port();
}

}  // namespace drivegate::slave
