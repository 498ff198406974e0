#include "server.h"

#include <spdlog/spdlog.h>

#include <boost/asio/ip/v6_only.hpp>
#include <vector>

#include "connection.h"
#include "server_state.h"

namespace drivegate::modbus {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

// Back-off before accepting again after a resource error (EMFILE, ENFILE, ENOBUFS, ENOMEM), so a
// full descriptor table does not turn the accept loop into a busy loop.
constexpr std::chrono::milliseconds kAcceptRetry{100};
// At most one warning per second about refused clients (the count says how many).
constexpr std::chrono::seconds kRefusalWarningInterval{1};

std::error_code to_std(const boost::system::error_code& ec) {
  return {ec.value(), std::system_category()};
}

bool parse_host(std::string host, asio::ip::address& out, bool& any) {
  any = host.empty() || host == "*";
  if (any) {
    out = asio::ip::address_v6::any();
    return true;
  }
  if (host == "localhost") host = "127.0.0.1";
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  boost::system::error_code ec;
  out = asio::ip::make_address(host, ec);
  return !ec;
}

void accept(const std::shared_ptr<ServerState>& state);

void on_accept(const std::shared_ptr<ServerState>& state, const boost::system::error_code& ec,
               tcp::socket socket) {
  if (state->closed || ec == asio::error::operation_aborted) return;
  if (ec) {
    state->log->warn("modbus: accept failed: {}", ec.message());
    if (ec == asio::error::no_descriptors || ec == asio::error::no_buffer_space ||
        ec == asio::error::no_memory || ec.value() == ENFILE) {
      state->retry_timer.expires_after(kAcceptRetry);
      state->retry_timer.async_wait([state](const boost::system::error_code& e) {
        if (!e && !state->closed) accept(state);
      });
      return;
    }
    accept(state);
    return;
  }
  if (state->live.size() >= state->options.max_clients) {
    // Past the cap: accepted and closed at once, so the client sees a clean close instead of a
    // connect that hangs in the backlog.
    ++state->stats.connections_refused;
    ++state->refused_since_warning;
    const auto now = std::chrono::steady_clock::now();
    if (now - state->last_refusal_warning >= kRefusalWarningInterval) {
      state->log->warn("modbus: {} client(s) refused: {} clients connected, max_clients = {}",
                       state->refused_since_warning, state->live.size(),
                       state->options.max_clients);
      state->last_refusal_warning = now;
      state->refused_since_warning = 0;
    }
    boost::system::error_code ignored;
    socket.close(ignored);
  } else {
    std::make_shared<Connection>(state, std::move(socket))->start();
  }
  accept(state);
}

void accept(const std::shared_ptr<ServerState>& state) {
  state->acceptor.async_accept([state](const boost::system::error_code& ec, tcp::socket socket) {
    on_accept(state, ec, std::move(socket));
  });
}

}  // namespace

Server::Server(asio::io_context& io, Backend& backend, ServerOptions options,
               std::shared_ptr<spdlog::logger> log)
    : state_(std::make_shared<ServerState>(io, backend, std::move(options), std::move(log))) {}

Server::~Server() {
  close();
}

std::error_code Server::listen() {
  auto& acceptor = state_->acceptor;
  asio::ip::address address;
  bool any = false;
  if (!parse_host(state_->options.host, address, any)) {
    return std::make_error_code(std::errc::invalid_argument);
  }
  boost::system::error_code ec;
  tcp::endpoint endpoint(address, state_->options.port);
  acceptor.open(endpoint.protocol(), ec);
  if (ec && any) {  // no IPv6 on this host: every IPv4 interface instead
    endpoint = tcp::endpoint(asio::ip::address_v4::any(), state_->options.port);
    acceptor.open(endpoint.protocol(), ec);
  }
  if (ec) return to_std(ec);
  acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (endpoint.protocol() == tcp::v6() && any) {
    acceptor.set_option(asio::ip::v6_only(false), ec);  // dual stack: IPv4 clients too
  }
  acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(state_->options.listen_backlog, ec);
  if (ec) {
    boost::system::error_code ignored;
    acceptor.close(ignored);
    return to_std(ec);
  }
  const auto bound = acceptor.local_endpoint(ec);
  state_->log->info("modbus: listening on {}:{} (max_clients {})", bound.address().to_string(),
                    bound.port(), state_->options.max_clients);
  accept(state_);
  return {};
}

tcp::endpoint Server::local_endpoint() const {
  boost::system::error_code ec;
  return state_->acceptor.local_endpoint(ec);
}

void Server::set_limits(const ServerLimits& limits) {
  auto& o = state_->options;
  o.max_clients = limits.max_clients;  // on_accept reads it for each new client
  o.frame_timeout = limits.frame_timeout;
  o.idle_timeout = limits.idle_timeout;
  // A copy, as in close(): the loop must not depend on what a connection does to `live`.
  const std::vector<Connection*> open(state_->live.begin(), state_->live.end());
  for (Connection* c : open) c->limits_changed();
}

ServerLimits Server::limits() const {
  return state_->options.limits();
}

const ServerStats& Server::stats() const {
  return state_->stats;
}

std::size_t Server::client_count() const {
  return state_->live.size();
}

void Server::close() {
  if (state_->closed) return;
  state_->closed = true;
  boost::system::error_code ignored;
  state_->acceptor.close(ignored);
  state_->retry_timer.cancel();
  const std::vector<Connection*> open(state_->live.begin(), state_->live.end());
  for (Connection* c : open) c->close();
}

}  // namespace drivegate::modbus
