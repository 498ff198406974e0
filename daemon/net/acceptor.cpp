#include "net/acceptor.h"

#include <boost/asio/error.hpp>
#include <boost/asio/ip/v6_only.hpp>
#include <cerrno>

namespace drivegate::net {

namespace asio = boost::asio;
using asio::ip::tcp;

bool accept_needs_back_off(const boost::system::error_code& ec) {
  return ec == asio::error::no_descriptors || ec == asio::error::no_buffer_space ||
         ec == asio::error::no_memory ||
         (ec.category() == boost::system::system_category() && ec.value() == ENFILE);
}

Acceptor::Acceptor(asio::io_context& io, Clock& clock, std::shared_ptr<spdlog::logger> log,
                   std::string name, AllowList allow)
    : clock_(clock),
      log_(std::move(log)),
      name_(std::move(name)),
      allow_(std::move(allow)),
      acceptor_(io),
      retry_(io.get_executor(), clock) {}

std::error_code Acceptor::bind(std::string_view host_text, std::uint16_t port, int backlog,
                               AnyAddress any) {
  const auto host = parse_listen_host(host_text);
  if (!host) return std::make_error_code(std::errc::invalid_argument);
  const bool every = host->any;
  tcp::endpoint endpoint(
      every && any == AnyAddress::ipv4 ? asio::ip::address_v4::any() : host->address, port);
  boost::system::error_code ec;
  acceptor_.open(endpoint.protocol(), ec);
  if (ec && every && any == AnyAddress::dual_stack) {  // no IPv6 here: every IPv4 interface
    endpoint = tcp::endpoint(asio::ip::address_v4::any(), port);
    acceptor_.open(endpoint.protocol(), ec);
  }
  if (!ec) acceptor_.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec && every && endpoint.protocol() == tcp::v6()) {
    acceptor_.set_option(asio::ip::v6_only(false), ec);  // dual stack: IPv4 clients too
  }
  if (!ec) acceptor_.bind(endpoint, ec);
  if (!ec) acceptor_.listen(backlog, ec);
  if (ec) {
    boost::system::error_code ignored;
    acceptor_.close(ignored);
    return {ec.value(), std::system_category()};
  }
  return {};
}

tcp::endpoint Acceptor::local_endpoint() const {
  boost::system::error_code ec;
  return acceptor_.local_endpoint(ec);
}

void Acceptor::start(Admit admit, Take take) {
  admit_ = std::move(admit);
  take_ = std::move(take);
  accept();
}

void Acceptor::close() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ignored;
  acceptor_.close(ignored);
  retry_.cancel();
  // The server's callbacks hold the server's state, which holds this: let go of them.
  admit_ = nullptr;
  take_ = nullptr;
}

void Acceptor::accept() {
  acceptor_.async_accept(
      [self = shared_from_this()](const boost::system::error_code& ec, tcp::socket socket) {
        self->on_accept(ec, std::move(socket));
      });
}

void Acceptor::accept_after(std::chrono::milliseconds wait) {
  retry_.expires_after(wait);
  retry_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    if (!ec && !self->closed_) self->accept();
  });
}

void Acceptor::on_accept(const boost::system::error_code& ec, tcp::socket socket) {
  if (closed_ || ec == asio::error::operation_aborted) return;
  if (ec) {
    // The peer gone before it was taken: the next accept works. Out of descriptors or memory, the
    // client stays in the backlog and the next accept fails at once the same way. The warning is
    // throttled: a full descriptor table fails every accept.
    if (const auto held = error_log_.admit(clock_.now())) {
      log_->warn("{}: accept failed: {}{}", name_, ec.message(), held_note(*held));
    }
    if (accept_needs_back_off(ec)) {
      accept_after(kAcceptRetry);
    } else {
      accept();
    }
    return;
  }
  boost::system::error_code peer_ec;
  const auto peer = socket.remote_endpoint(peer_ec);
  boost::system::error_code ignored;
  if (peer_ec || !allowed(allow_, peer.address())) {
    ++stats_.not_allowed;
    if (const auto held = not_allowed_log_.admit(clock_.now())) {
      log_->warn("{}: {} client(s) closed at accept, not in the allow list (last: {})", name_,
                 *held + 1, peer_ec ? peer_ec.message() : peer.address().to_string());
    }
    socket.close(ignored);
    accept();
    return;
  }
  switch (admit_(peer.address())) {
    case Admission::take:
      ++stats_.accepted;
      ++stats_.active;
      take_(std::move(socket));
      break;
    case Admission::refuse:
      ++stats_.refused;
      socket.close(ignored);
      break;
    case Admission::hold_off:
      socket.close(ignored);
      accept_after(kHoldOff);
      return;
  }
  if (!closed_) accept();
}

}  // namespace drivegate::net
