#include "server.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <boost/asio/ip/v6_only.hpp>
#include <vector>

#include "connection.h"
#include "net/accept_errors.h"
#include "net/listen_host.h"
#include "server_state.h"

namespace drivegate::modbus {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

std::error_code to_std(const boost::system::error_code& ec) {
  return {ec.value(), std::system_category()};
}

using Listener = std::shared_ptr<ListenerState>;

void accept(const std::shared_ptr<ServerState>& state, const Listener& listener);

std::string allow_text(const net::AllowList& allow) {
  std::string out;
  for (const auto& r : allow) out += (out.empty() ? "" : ", ") + r.to_string();
  return out;
}

std::size_t slots(const ServerState& state, const ListenerState& listener) {
  return listener.options.policy.max_clients.value_or(state.options.max_clients);
}

// Whether a new client fits on `listener`: a free slot, or the listener's longest-idle read-only
// client closed to make one (a read client that went quiet gives way to a PLC that wants in;
// clients of other listeners are never touched).
bool make_room(ServerState& state, ListenerState& listener) {
  if (listener.stats.connections_active < slots(state, listener)) return true;
  Connection* oldest = nullptr;
  std::chrono::steady_clock::time_point since = std::chrono::steady_clock::time_point::max();
  for (Connection* c : state.live) {
    if (&c->listener() != &listener) continue;
    if (const auto idle = c->evictable_since(); idle && *idle < since) {
      since = *idle;
      oldest = c;
    }
  }
  if (oldest == nullptr) return false;
  const auto now = std::chrono::steady_clock::now();
  if (const auto held = listener.evicted_log.admit(now)) {
    state.log->info(
        "modbus: {}: full ({} clients): closed the read-only client idle longest "
        "({} ms) for a new one{}",
        listener.options.name(), listener.stats.connections_active,
        std::chrono::duration_cast<std::chrono::milliseconds>(now - since).count(),
        net::held_note(*held));
  }
  oldest->evict();
  return listener.stats.connections_active < slots(state, listener);
}

// A TLS listener lets each client address start so many handshakes a second (net/address_rate.h):
// a handshake costs a private-key signature on the event loop every other client waits on, so
// a flood from one address is closed at accept instead. Plain listeners have no handshake.
bool handshake_allowed(ServerState& state, ListenerState& listener, const asio::ip::address& peer) {
  if (!listener.tls) return true;
  const auto now = std::chrono::steady_clock::now();
  if (listener.handshakes.admit(peer, now)) return true;
  ++state.stats.tls_handshakes_limited;
  ++listener.stats.tls_handshakes_limited;
  if (const auto held = listener.limited_log.admit(now)) {
    state.log->warn(
        "modbus: {}: {} closed at accept: more than {} TLS handshakes a second from "
        "it{}",
        listener.options.name(), peer.to_string(), listener.options.policy.handshakes.per_second,
        net::held_note(*held));
  }
  return false;
}

// How long a TLS listener waits before its next accept after it closed one over the handshake
// limit (bench/flood.sh measures what a flood costs the other listeners' clients).
constexpr std::chrono::milliseconds kAfterLimitedHandshake{5};

// Closes a just-accepted socket before a byte of it is read.
void refuse(tcp::socket& socket) {
  boost::system::error_code ignored;
  socket.close(ignored);
}

void on_accept(const std::shared_ptr<ServerState>& state, const Listener& listener,
               const boost::system::error_code& ec, tcp::socket socket) {
  if (state->closed || ec == asio::error::operation_aborted) return;
  if (ec) {
    net::after_accept_error(ec, "modbus: " + listener->options.name(), *state->log,
                            listener->accept_error_log, listener->retry_timer, [state, listener] {
                              if (!state->closed) accept(state, listener);
                            });
    return;
  }
  boost::system::error_code peer_ec;
  const auto peer = socket.remote_endpoint(peer_ec);
  if (peer_ec || !net::allowed(listener->options.policy.allow, peer.address())) {
    // Not in the allow list: closed at accept, before anything it sent is read.
    ++state->stats.connections_not_allowed;
    ++listener->stats.connections_not_allowed;
    if (const auto held = listener->not_allowed_log.admit(std::chrono::steady_clock::now())) {
      state->log->warn(
          "modbus: {}: {} client(s) closed at accept, not in the allow list (last: {})",
          listener->options.name(), *held + 1,
          peer_ec ? peer_ec.message() : peer.address().to_string());
    }
    refuse(socket);
  } else if (!handshake_allowed(*state, *listener, peer.address())) {
    refuse(socket);
    // A flood costs the loop an accept and a close per connection even so, and the flooding
    // client's connects cost the machine as much again; the listener takes its next connection
    // a moment later, so that at most 200 refusals a second reach the loop whatever the flood's
    // rate (the rest wait in the kernel's backlog). Only this TLS listener's newcomers wait for
    // it, behind the flood's queued connections: 5 ms each (bench/flood.sh: with 1 ms the flood
    // still cost a plaintext PLC's p99 5x, with 5 ms 1.3x).
    listener->retry_timer.expires_after(kAfterLimitedHandshake);
    listener->retry_timer.async_wait([state, listener](const boost::system::error_code& waited) {
      if (!waited && !state->closed) accept(state, listener);
    });
    return;
  } else if (!make_room(*state, *listener)) {
    // Full, and every client on it reads and writes or is busy: accepted and closed at once, so
    // the client sees a clean close instead of a connect that hangs in the backlog.
    ++state->stats.connections_refused;
    ++listener->stats.connections_refused;
    if (const auto held = listener->refused_log.admit(std::chrono::steady_clock::now())) {
      state->log->warn(
          "modbus: {}: {} client(s) refused: {} clients connected, max_clients = {}, none of them "
          "an idle read-only one to give way",
          listener->options.name(), *held + 1, listener->stats.connections_active,
          slots(*state, *listener));
    }
    refuse(socket);
  } else {
    std::make_shared<Connection>(state, listener, std::move(socket))->start();
  }
  accept(state, listener);
}

void accept(const std::shared_ptr<ServerState>& state, const Listener& listener) {
  listener->acceptor.async_accept(
      [state, listener](const boost::system::error_code& ec, tcp::socket socket) {
        on_accept(state, listener, ec, std::move(socket));
      });
}

std::error_code bind(ListenerState& l, int backlog) {
  auto& acceptor = l.acceptor;
  const auto host = net::parse_listen_host(l.options.host);
  if (!host) return std::make_error_code(std::errc::invalid_argument);
  const auto& [address, any] = *host;
  boost::system::error_code ec;
  tcp::endpoint endpoint(address, l.options.port);
  acceptor.open(endpoint.protocol(), ec);
  if (ec && any) {  // no IPv6 on this host: every IPv4 interface instead
    endpoint = tcp::endpoint(asio::ip::address_v4::any(), l.options.port);
    acceptor.open(endpoint.protocol(), ec);
  }
  if (ec) return to_std(ec);
  acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (endpoint.protocol() == tcp::v6() && any) {
    acceptor.set_option(asio::ip::v6_only(false), ec);  // dual stack: IPv4 clients too
  }
  acceptor.bind(endpoint, ec);
  if (!ec) acceptor.listen(backlog, ec);
  if (ec) {
    boost::system::error_code ignored;
    acceptor.close(ignored);
    return to_std(ec);
  }
  return {};
}

bool same_socket(const ListenerOptions& a, const ListenerOptions& b) {
  return a.host == b.host && a.port == b.port &&
         a.policy.tls.has_value() == b.policy.tls.has_value();
}

}  // namespace

Server::Server(asio::io_context& io, Backend& backend, ServerOptions options,
               std::shared_ptr<spdlog::logger> log)
    : state_(std::make_shared<ServerState>(io, backend, std::move(options), std::move(log))) {
  for (const auto& l : state_->options.listeners) {
    state_->listeners.push_back(std::make_shared<ListenerState>(io, l));
  }
}

Server::~Server() {
  close();
}

std::error_code Server::listen() {
  auto& log = *state_->log;
  for (const auto& l : state_->listeners) {
    if (const auto& tls = l->options.policy.tls) {
      std::string error;
      l->tls = make_tls_context(*tls, error);
      if (!l->tls) {
        log.error("modbus: {}: {}", l->options.name(), error);
        return std::make_error_code(std::errc::invalid_argument);
      }
    }
  }
  for (const auto& l : state_->listeners) {
    if (const auto ec = bind(*l, state_->options.listen_backlog)) {
      log.error("modbus: cannot listen on {}: {}", l->options.name(), ec.message());
      for (const auto& other : state_->listeners) {
        boost::system::error_code ignored;
        other->acceptor.close(ignored);
      }
      return ec;
    }
  }
  for (const auto& l : state_->listeners) {
    boost::system::error_code ec;
    const auto bound = l->acceptor.local_endpoint(ec);
    const auto& p = l->options.policy;
    log.info("modbus: listening on {}:{}{}: access {}{}, {} word order, allow {}",
             bound.address().to_string(), bound.port(), p.tls ? " (TLS, client certificates)" : "",
             to_string(p.access), p.tls ? " without a known role" : "", to_string(p.word_order),
             net::allows_everyone(p.allow) ? std::string("every address") : allow_text(p.allow));
    accept(state_, l);
  }
  for (const auto& l : state_->listeners) {
    log.info("modbus: {}: max_clients {}{}", l->options.name(), slots(*state_, *l),
             l->options.policy.max_clients ? "" : " ([server] max_clients)");
  }
  return {};
}

Server::ReloadResult Server::reload_listeners(const std::vector<ListenerOptions>& next) {
  ReloadResult result;
  // Everything that can fail is done first; only then is anything changed.
  std::vector<std::pair<Listener, std::shared_ptr<asio::ssl::context>>> plan;
  for (const auto& n : next) {
    const auto it = std::find_if(state_->listeners.begin(), state_->listeners.end(),
                                 [&](const Listener& l) { return same_socket(l->options, n); });
    if (it == state_->listeners.end()) {
      result.restart_needed.push_back(n.name());
      continue;
    }
    std::shared_ptr<asio::ssl::context> tls;
    if (n.policy.tls) {
      std::string error;
      tls = make_tls_context(*n.policy.tls, error);  // re-read: certificates may have been renewed
      if (!tls) {
        result.errors.push_back(n.name() + ": " + error);
        continue;
      }
    }
    plan.emplace_back(*it, std::move(tls));
  }
  for (const auto& l : state_->listeners) {
    if (std::none_of(next.begin(), next.end(),
                     [&](const ListenerOptions& n) { return same_socket(l->options, n); })) {
      result.restart_needed.push_back(l->options.name() + " (removed)");
    }
  }
  if (!result.errors.empty()) return result;
  for (auto& step : plan) {
    ListenerState& listener = *step.first;
    const auto n = std::find_if(next.begin(), next.end(), [&](const ListenerOptions& o) {
      return same_socket(listener.options, o);
    });
    listener.options.policy = n->policy;
    listener.handshakes.set_limit(n->policy.handshakes);
    listener.tls = std::move(step.second);
  }
  const std::vector<Connection*> open(state_->live.begin(), state_->live.end());
  for (Connection* c : open) c->policy_changed();
  return result;
}

tcp::endpoint Server::local_endpoint(std::size_t listener) const {
  boost::system::error_code ec;
  return state_->listeners.at(listener)->acceptor.local_endpoint(ec);
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

std::size_t Server::listener_count() const {
  return state_->listeners.size();
}

const ListenerOptions& Server::listener(std::size_t i) const {
  return state_->listeners.at(i)->options;
}

const ListenerStats& Server::listener_stats(std::size_t i) const {
  return state_->listeners.at(i)->stats;
}

std::size_t Server::client_count() const {
  return state_->live.size();
}

void Server::close() {
  if (state_->closed) return;
  state_->closed = true;
  for (const auto& l : state_->listeners) {
    boost::system::error_code ignored;
    l->acceptor.close(ignored);
    l->retry_timer.cancel();
  }
  const std::vector<Connection*> open(state_->live.begin(), state_->live.end());
  for (Connection* c : open) c->close();
}

}  // namespace drivegate::modbus
