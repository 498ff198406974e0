// The northbound Modbus TCP server: an acceptor on host:port and one Connection per client, all
// on the caller's io_context (single-threaded; nothing here blocks). Requests are dispatched
// against a Backend; see backend.h for the contract.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "backend.h"
#include "net/clock.h"
#include "server_options.h"

namespace spdlog {
class logger;
}

namespace drivegate::modbus {

struct ServerState;

class Server {
 public:
  // `backend` must outlive the io_context's processing of this server's handlers.
  // Every timeout of the server and its connections is measured on `clock` (net/clock.h), which
  // must outlive the server.
  Server(boost::asio::io_context& io, net::Clock& clock, Backend& backend, ServerOptions options,
         std::shared_ptr<spdlog::logger> log);
  ~Server();  // close()
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Binds every listener, reads the TLS files of those that have them, and starts accepting.
  // All or nothing: on an error (an address that does not parse, a TLS file refused, the
  // system's) nothing listens; the error is logged naming the listener.
  std::error_code listen();
  // The bound endpoint (and port, useful with port 0) of a listener, in ServerOptions order, once
  // listen() succeeded.
  boost::asio::ip::tcp::endpoint local_endpoint(std::size_t listener = 0) const;
  std::uint16_t port(std::size_t listener = 0) const { return local_endpoint(listener).port(); }

  struct ReloadResult {
    std::vector<std::string> errors;          // nothing was changed (a TLS file refused...)
    std::vector<std::string> restart_needed;  // listeners added or removed: at the next start
  };
  // New policies for the running listeners (SIGHUP), matched by address and TLS-ness: allow
  // lists, access levels, word order, roles, and the TLS files, re-read (renewed certificates
  // serve new handshakes; a connection keeps the context it started with). Open connections take
  // the new access level and word order at once; one whose address is no longer allowed is
  // closed. A listener that would be added or removed, or whose address changed, is reported
  // and waits for a restart. All or nothing: when `errors` is not empty nothing changed.
  ReloadResult reload_listeners(const std::vector<ListenerOptions>& listeners);

  // New limits while running, without closing or pausing anything. Call on the io_context's
  // thread (like everything here). The exact rule:
  // - max_clients is read at each accept: clients accepted from now on are counted against it.
  //   Lowering it below the number connected closes no one (the oldest are never dropped); new
  //   clients are refused until enough have left.
  // - idle_timeout and frame_timeout apply to every open connection at once, measured from the
  //   same instants as before (its last request; the first byte of its pending partial frame), as
  //   if they had always been in force: a connection already silent for longer than the new
  //   idle_timeout is closed when its re-armed timer fires, in a later turn of the event loop,
  //   never inside this call. A timer already armed for an earlier instant is left as it is: it
  //   finds nothing due, and re-arms for the deadline the new values give.
  // host, port, listen_backlog, max_pending_writes and identity cannot change while running.
  void set_limits(const ServerLimits& limits);
  ServerLimits limits() const;

  // Every listener's counters added up.
  ServerStats stats() const;
  // Each listener, in ServerOptions order: its options (the policy in force) and counters.
  std::size_t listener_count() const;
  const ListenerOptions& listener(std::size_t i) const;
  ListenerStats listener_stats(std::size_t i) const;
  std::size_t client_count() const;

  // Stops accepting and closes every connection. Replies to pending writes are dropped. Once the
  // backend has called every pending `done`, nothing of this server is left on the io_context.
  void close();

 private:
  std::shared_ptr<ServerState> state_;
};

}  // namespace drivegate::modbus
