// The one acceptor of every network server of the daemon (the Modbus listeners, the status page):
// a listening socket and the sequence each new client goes through, the same for every protocol.
//   1. accept() failing: warn (throttled), and back off when out of descriptors or memory
//      (accepting again at once would spin on the same error and starve every other client);
//   2. the peer not in the allow list: closed before a byte of it is read (`not_allowed`);
//   3. the server's own rule (Admit): take it, refuse it (full: `refused`), or refuse it and hold
//      the next accept off a moment (a flood rule: a TLS listener's handshake rate);
//   4. taken: handed to the server (Take), counted `accepted` and `active` until left().
// The counters are the listener's; a server with several listeners derives its totals from them.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <system_error>

#include "net/allow_list.h"
#include "net/clock.h"
#include "net/listen_host.h"
#include "net/log_throttle.h"

namespace drivegate::net {

struct AcceptStats {
  std::uint64_t accepted = 0;     // clients taken and served
  std::uint64_t active = 0;       // of them, connected now
  std::uint64_t not_allowed = 0;  // closed at accept: not in the allow list
  std::uint64_t refused = 0;      // closed at accept: the server full
};

// What the server says of a client the allow list let through.
enum class Admission : std::uint8_t {
  take,      // served
  refuse,    // closed at once and counted `refused`: the server is full
  hold_off,  // closed at once, and the next accept waits kHoldOff (the server counts why)
};

// "*" or "": which "every interface" a server listens on.
enum class AnyAddress : std::uint8_t {
  dual_stack,  // IPv6 and IPv4 (IPv4 alone where the host has no IPv6)
  ipv4,        // every IPv4 interface
};

// How long accept() waits after a client failed with an error that will fail the next one too.
inline constexpr std::chrono::milliseconds kAcceptRetry{100};
// How long the next accept waits after a hold_off (bench/flood.sh measures what a handshake flood
// costs the other listeners' clients: with 1 ms it still cost a plaintext PLC's p99 5x, with
// 5 ms 1.3x). At most 200 refusals a second reach the event loop whatever the flood's rate; the
// rest wait in the kernel's backlog, and only this listener's newcomers wait behind them.
inline constexpr std::chrono::milliseconds kHoldOff{5};

// EMFILE, ENFILE, ENOBUFS, ENOMEM: the errors after which accept() backs off.
bool accept_needs_back_off(const boost::system::error_code& ec);

class Acceptor : public std::enable_shared_from_this<Acceptor> {
 public:
  using Admit = std::function<Admission(const boost::asio::ip::address& peer)>;
  using Take = std::function<void(boost::asio::ip::tcp::socket socket)>;

  // `name` starts its log lines ("modbus: 127.0.0.1:502", "http").
  Acceptor(boost::asio::io_context& io, Clock& clock, std::shared_ptr<spdlog::logger> log,
           std::string name, AllowList allow);
  Acceptor(const Acceptor&) = delete;
  Acceptor& operator=(const Acceptor&) = delete;

  // Opens, binds and listens on `host` (net/listen_host.h: a host that does not parse is
  // invalid_argument); on an error nothing is left open.
  std::error_code bind(std::string_view host, std::uint16_t port, int backlog, AnyAddress any);
  // Accepts until close(). The callbacks are dropped at close().
  void start(Admit admit, Take take);
  // Stops accepting; clients already taken are the server's to close.
  void close();

  // Who may connect from now on (a reload); clients already taken are the server's to check.
  void set_allow(AllowList allow) { allow_ = std::move(allow); }
  [[nodiscard]] const AllowList& allow() const { return allow_; }
  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] boost::asio::ip::tcp::endpoint local_endpoint() const;

  // A taken client has gone.
  void left() { --stats_.active; }
  [[nodiscard]] const AcceptStats& stats() const { return stats_; }

 private:
  void accept();
  void on_accept(const boost::system::error_code& ec, boost::asio::ip::tcp::socket socket);
  void accept_after(std::chrono::milliseconds wait);

  Clock& clock_;
  const std::shared_ptr<spdlog::logger> log_;
  const std::string name_;
  AllowList allow_;
  boost::asio::ip::tcp::acceptor acceptor_;
  Timer retry_;  // the next accept, after a back-off or a hold-off
  Admit admit_;
  Take take_;
  bool closed_ = false;
  AcceptStats stats_;
  LogThrottle error_log_;        // accept() failing (out of descriptors and the like)
  LogThrottle not_allowed_log_;  // clients closed at accept: not in the allow list
};

}  // namespace drivegate::net
