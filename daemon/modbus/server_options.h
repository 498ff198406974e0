// Settings of the Modbus TCP server and the counters it keeps.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "net/address_rate.h"
#include "net/allow_list.h"
#include "net/listen_host.h"
#include "pdu.h"
#include "tls.h"

namespace drivegate::modbus {

// The settings that may change while the server runs (Server::set_limits). Their meaning is that
// of the ServerOptions fields of the same names.
struct ServerLimits {
  std::size_t max_clients;
  std::chrono::milliseconds frame_timeout;
  std::chrono::milliseconds idle_timeout;
  friend bool operator==(const ServerLimits&, const ServerLimits&) = default;
};

// Who a listener serves and what they may do. Everything but host, port and whether it speaks
// TLS may change while it runs (Server::reload_listeners).
struct ListenerPolicy {
  net::AllowList allow;  // client addresses served; empty: every address
  // Plain TCP: every client's level. TLS: the level of a client whose certificate carries no
  // role in tls->roles.
  AccessLevel access = AccessLevel::maintain;
  WordOrder word_order = WordOrder::big;
  std::optional<TlsOptions> tls;  // Modbus/TCP Security: TLS, client certificate required
  // This listener's own connection slots; none: ServerOptions::max_clients. Clients of other
  // listeners never take them.
  std::optional<std::size_t> max_clients;
  // TLS handshakes one client address may start (net/address_rate.h): past it a new connection from
  // that address is closed at accept, before the handshake's signature costs the event loop.
  net::RateLimit handshakes = net::RateLimit::per_second_in_bursts_of_two(5);
  friend bool operator==(const ListenerPolicy&, const ListenerPolicy&) = default;
};

struct ListenerOptions {
  // A numeric IPv4 or IPv6 address ("[::1]" accepted), "localhost" (127.0.0.1), or "" / "*" for
  // every interface (IPv6 dual stack, IPv4 only where IPv6 is unavailable). No DNS lookup: it
  // would block the event loop.
  std::string host = "*";
  std::uint16_t port = 502;  // 0: an ephemeral port, see Server::port()
  ListenerPolicy policy;

  // "host:port" (and " (TLS)"), as the log names it.
  [[nodiscard]] std::string name() const {
    return net::listen_name(host, port, policy.tls.has_value());
  }
};

// Fixed for the server's life, except the three of ServerLimits and the listeners' policies.
struct ServerOptions {
  std::vector<ListenerOptions> listeners{ListenerOptions{}};  // at least one
  // Each listener's connection slots unless its policy gives its own. A full listener closes
  // its longest-idle read-only client for a new one; with none, the new one is closed at once.
  std::size_t max_clients = 32;
  std::size_t max_pending_writes = 16;  // per connection; at the cap the connection stops reading
  std::chrono::milliseconds frame_timeout{2000};  // a partial frame older than this closes; 0 = off
  std::chrono::milliseconds idle_timeout{60000};  // no request for this long closes; 0 = off
  int listen_backlog = 128;
  DeviceIdentity identity;

  ServerLimits limits() const { return {max_clients, frame_timeout, idle_timeout}; }
};

// What a listener counts, for /metrics and the status page. The server's totals are the same
// counters, every listener's added up (Server::stats()): nothing is counted twice.
struct ListenerStats {
  // Through the listener's acceptor (net/acceptor.h).
  std::uint64_t connections_accepted = 0;  // served connections (refused ones not included)
  std::uint64_t connections_active = 0;
  std::uint64_t connections_not_allowed = 0;  // closed at once: address not in the allow list
  std::uint64_t connections_refused = 0;      // closed at once: the listener full, none to evict
  // The server's own.
  std::uint64_t connections_evicted = 0;     // idle read-only clients closed for a new client
  std::uint64_t tls_handshake_failures = 0;  // closed: no valid client certificate, not TLS...
  std::uint64_t tls_handshakes_limited = 0;  // closed at accept: the address's handshake rate
  std::uint64_t writes_denied = 0;   // writes answered 01: beyond the connection's access level
  std::uint64_t bytes_received = 0;  // what its clients sent (TLS: after decryption)
  std::uint64_t requests = 0;        // well-formed requests dispatched
  std::uint64_t responses = 0;       // responses and exceptions queued for sending
  std::uint64_t malformed = 0;       // connections closed on a malformed MBAP header
  std::uint64_t frame_timeouts = 0;  // connections closed with a stale partial frame
  std::uint64_t idle_timeouts = 0;   // connections closed for lack of requests
  // Writes that settled (applied or not) after their client had gone: it was never told.
  std::uint64_t writes_unanswered = 0;
  // by_function[function code]: requests (0x2B is the largest served; others counted in [0]).
  std::array<std::uint64_t, 0x2C> by_function{};
  // exceptions[code]: exception responses sent, by code (Application Protocol section 7;
  // codes 0x01..0x0B, larger codes counted in [0]).
  std::array<std::uint64_t, 12> exceptions{};

  ListenerStats& operator+=(const ListenerStats& o);
};

// Every listener's counters added up.
using ServerStats = ListenerStats;

}  // namespace drivegate::modbus
