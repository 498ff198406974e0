#include "server.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <vector>

#include "connection.h"
#include "server_state.h"

namespace drivegate::modbus {
namespace {

namespace asio = boost::asio;
using asio::ip::tcp;

using Listener = std::shared_ptr<ListenerState>;

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
  const auto connected = [&] { return listener.acceptor->stats().active; };
  if (connected() < slots(state, listener)) return true;
  Connection* oldest = nullptr;
  net::TimePoint since = net::TimePoint::max();
  for (Connection* c : state.live) {
    if (&c->listener() != &listener) continue;
    if (const auto idle = c->evictable_since(); idle && *idle < since) {
      since = *idle;
      oldest = c;
    }
  }
  if (oldest == nullptr) return false;
  const auto now = state.clock.now();
  if (const auto held = listener.evicted_log.admit(now)) {
    state.log->info(
        "modbus: {}: full ({} clients): closed the read-only client idle longest "
        "({} ms) for a new one{}",
        listener.options.name(), connected(),
        std::chrono::duration_cast<std::chrono::milliseconds>(now - since).count(),
        net::held_note(*held));
  }
  oldest->evict();
  return connected() < slots(state, listener);
}

// A TLS listener lets each client address start so many handshakes a second (net/address_rate.h):
// a handshake costs a private-key signature on the handshake thread (handshaker.h), which every
// other TLS client's handshake waits on, so a flood from one address is closed at accept instead.
// Plain listeners have no handshake.
bool handshake_allowed(ServerState& state, ListenerState& listener, const asio::ip::address& peer) {
  if (!listener.tls) return true;
  const auto now = state.clock.now();
  if (listener.handshakes.admit(peer, now)) return true;
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

// The listener's rule for a client its allow list let through: the handshake rate (a flood is
// held off: net::kHoldOff), then a slot.
net::Admission admit(ServerState& state, ListenerState& listener, const asio::ip::address& peer) {
  if (!handshake_allowed(state, listener, peer)) return net::Admission::hold_off;
  if (make_room(state, listener)) return net::Admission::take;
  // Full, and every client on it reads and writes or is busy: accepted and closed at once, so
  // the client sees a clean close instead of a connect that hangs in the backlog.
  if (const auto held = listener.refused_log.admit(state.clock.now())) {
    state.log->warn(
        "modbus: {}: {} client(s) refused: {} clients connected, max_clients = {}, none of them "
        "an idle read-only one to give way",
        listener.options.name(), *held + 1, listener.acceptor->stats().active,
        slots(state, listener));
  }
  return net::Admission::refuse;
}

void start_accepting(const std::shared_ptr<ServerState>& state, const Listener& listener) {
  listener->acceptor->start(
      [state, listener](const asio::ip::address& peer) { return admit(*state, *listener, peer); },
      [state, listener](tcp::socket socket) {
        std::make_shared<Connection>(state, listener, std::move(socket))->start();
      });
}

bool same_socket(const ListenerOptions& a, const ListenerOptions& b) {
  return a.host == b.host && a.port == b.port &&
         a.policy.tls.has_value() == b.policy.tls.has_value();
}

}  // namespace

ListenerStats& ListenerStats::operator+=(const ListenerStats& o) {
  connections_accepted += o.connections_accepted;
  connections_active += o.connections_active;
  connections_not_allowed += o.connections_not_allowed;
  connections_refused += o.connections_refused;
  connections_evicted += o.connections_evicted;
  tls_handshake_failures += o.tls_handshake_failures;
  tls_handshakes_limited += o.tls_handshakes_limited;
  writes_denied += o.writes_denied;
  bytes_received += o.bytes_received;
  requests += o.requests;
  responses += o.responses;
  malformed += o.malformed;
  frame_timeouts += o.frame_timeouts;
  idle_timeouts += o.idle_timeouts;
  writes_unanswered += o.writes_unanswered;
  for (std::size_t i = 0; i < by_function.size(); ++i) by_function[i] += o.by_function[i];
  for (std::size_t i = 0; i < exceptions.size(); ++i) exceptions[i] += o.exceptions[i];
  return *this;
}

ListenerStats ListenerState::counters() const {
  ListenerStats out = stats;
  const net::AcceptStats& a = acceptor->stats();
  out.connections_accepted = a.accepted;
  out.connections_active = a.active;
  out.connections_not_allowed = a.not_allowed;
  out.connections_refused = a.refused;
  return out;
}

Server::Server(asio::io_context& io, net::Clock& clock, Backend& backend, ServerOptions options,
               std::shared_ptr<spdlog::logger> log)
    : state_(
          std::make_shared<ServerState>(io, clock, backend, std::move(options), std::move(log))) {
  for (const auto& l : state_->options.listeners) {
    state_->listeners.push_back(std::make_shared<ListenerState>(io, clock, state_->log, l));
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
    const auto ec = l->acceptor->bind(l->options.host, l->options.port,
                                      state_->options.listen_backlog, net::AnyAddress::dual_stack);
    if (ec) {
      log.error("modbus: cannot listen on {}: {}", l->options.name(), ec.message());
      for (const auto& other : state_->listeners) other->acceptor->close();
      return ec;
    }
  }
  if (std::any_of(state_->listeners.begin(), state_->listeners.end(),
                  [](const Listener& l) { return l->tls != nullptr; })) {
    state_->handshaker = std::make_unique<Handshaker>(state_->io);
  }
  for (const auto& l : state_->listeners) {
    const auto bound = l->acceptor->local_endpoint();
    const auto& p = l->options.policy;
    log.info("modbus: listening on {}:{}{}: access {}{}, {} word order, allow {}",
             bound.address().to_string(), bound.port(), p.tls ? " (TLS, client certificates)" : "",
             to_string(p.access), p.tls ? " without a known role" : "", to_string(p.word_order),
             net::allows_everyone(p.allow) ? std::string("every address") : allow_text(p.allow));
    start_accepting(state_, l);
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
    listener.acceptor->set_allow(n->policy.allow);
    listener.handshakes.set_limit(n->policy.handshakes);
    listener.tls = std::move(step.second);
  }
  const std::vector<Connection*> open(state_->live.begin(), state_->live.end());
  for (Connection* c : open) c->policy_changed();
  return result;
}

tcp::endpoint Server::local_endpoint(std::size_t listener) const {
  return state_->listeners.at(listener)->acceptor->local_endpoint();
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

ServerStats Server::stats() const {
  ServerStats all;
  for (const auto& l : state_->listeners) all += l->counters();
  return all;
}

std::size_t Server::listener_count() const {
  return state_->listeners.size();
}

const ListenerOptions& Server::listener(std::size_t i) const {
  return state_->listeners.at(i)->options;
}

ListenerStats Server::listener_stats(std::size_t i) const {
  return state_->listeners.at(i)->counters();
}

std::size_t Server::client_count() const {
  return state_->live.size();
}

void Server::close() {
  if (state_->closed) return;
  state_->closed = true;
  for (const auto& l : state_->listeners) l->acceptor->close();
  const std::vector<Connection*> open(state_->live.begin(), state_->live.end());
  for (Connection* c : open) c->close();
  // Handshakes still in flight come back aborted, to connections already closed.
  if (state_->handshaker) state_->handshaker->stop();
}

}  // namespace drivegate::modbus
