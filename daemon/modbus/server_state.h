// What the acceptors and every connection of one server share. Owned through shared_ptr by the
// Server and by every pending handler, so a handler that runs after the Server is gone finds it
// intact (and closed).
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/context.hpp>
#include <chrono>
#include <memory>
#include <unordered_set>
#include <vector>

#include "backend.h"
#include "handshaker.h"
#include "net/acceptor.h"
#include "net/address_rate.h"
#include "net/clock.h"
#include "net/log_throttle.h"
#include "pdu.h"
#include "server_options.h"

namespace spdlog {
class logger;
}

namespace drivegate::modbus {

class Connection;

// One listening socket: its policy, the acceptor that takes its clients (net/acceptor.h), and
// the TLS context its handshakes use (replaced on reload; a connection keeps the one it started
// with).
struct ListenerState {
  ListenerState(boost::asio::io_context& io, net::Clock& clock,
                const std::shared_ptr<spdlog::logger>& log, ListenerOptions options_)
      : options(std::move(options_)),
        acceptor(std::make_shared<net::Acceptor>(io, clock, log, "modbus: " + options.name(),
                                                 options.policy.allow)),
        handshakes(options.policy.handshakes) {}

  // What it has counted with what its acceptor has (accepted, connected, not allowed, refused).
  [[nodiscard]] ListenerStats counters() const;

  ListenerOptions options;  // policy changed only by Server::reload_listeners
  std::shared_ptr<boost::asio::ssl::context> tls;  // set when options.policy.tls is
  std::shared_ptr<net::Acceptor> acceptor;
  net::LogThrottle handshake_log;  // TLS handshakes that failed or took too long
  net::LogThrottle refused_log;    // clients refused: full, none to evict
  net::LogThrottle evicted_log;    // idle read-only clients closed for a new one
  net::LogThrottle limited_log;    // TLS clients closed at accept: handshake rate
  // Writes beyond a connection's access level: once a connection, and paced across them, so
  // that a client connecting anew for every write does not flood the journal either.
  net::LogThrottle denied_log;
  net::AddressRate handshakes;  // TLS handshakes per client address
  ListenerStats stats;          // its own counts; the acceptor's four are in `acceptor`
};

struct ServerState {
  ServerState(boost::asio::io_context& io_context, net::Clock& clock_, Backend& backend_,
              ServerOptions options_, std::shared_ptr<spdlog::logger> log_)
      : io(io_context),
        clock(clock_),
        backend(backend_),
        options(std::move(options_)),
        log(std::move(log_)),
        dispatcher(backend_, options.identity) {}

  boost::asio::io_context& io;
  net::Clock& clock;  // every deadline of the server and its connections (net/clock.h)
  Backend& backend;
  // Changed only by Server::set_limits (max_clients, idle_timeout, frame_timeout); the rest is
  // fixed once the server is built (the write slots and the identity are sized and copied at
  // construction). options.listeners is the start-up list: each listener's current policy is in
  // its ListenerState.
  ServerOptions options;
  const std::shared_ptr<spdlog::logger> log;
  Dispatcher dispatcher;  // shared: single-threaded, and never re-entered (see Connection)
  std::vector<std::shared_ptr<ListenerState>> listeners;
  std::unordered_set<Connection*> live;  // open connections, every listener's
  // The TLS handshakes' thread, when a listener has TLS: started by Server::listen, stopped and
  // joined by Server::close.
  std::unique_ptr<Handshaker> handshaker;
  bool closed = false;
  net::LogThrottle malformed_log;      // frames that are not Modbus TCP
  net::LogThrottle frame_timeout_log;  // partial frames left unfinished
  net::LogThrottle unanswered_log;     // write results whose client had gone
};

}  // namespace drivegate::modbus
