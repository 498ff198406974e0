// The HTTP side (README, "Watching it"): the status page, its JSON, the register map and
// Prometheus metrics, served on the daemon's own event loop with Boost.Beast (no thread of its
// own). Hostile input gets the care Modbus gets: an allow list checked at accept, a client cap,
// bounded request headers and no request bodies, and a whole request within request_timeout
// (a slow client is closed). Read-only: no route writes to a drive.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <chrono>
#include <memory>
#include <string>
#include <system_error>

#include "content.h"
#include "http_stats.h"
#include "net/address_rate.h"
#include "net/allow_list.h"
#include "net/clock.h"

namespace drivegate::http {

struct HttpOptions {
  std::string host = "127.0.0.1";  // numeric, as for Modbus listeners
  std::uint16_t port = 8502;       // 0: ephemeral
  net::AllowList allow;            // empty: every address
  std::size_t max_clients = 16;    // past it a client is closed at accept (captures aside)
  // Requests one client address may have served a second, in bursts of `burst`; a request over
  // it waits for its turn (its connection is not read meanwhile), so one client hammering the
  // page slows itself, not the event loop that serves the PLCs. 0: no limit. A response counts
  // one request for every kBytesPerRequest it holds: its cost to the loop is its size.
  net::RateLimit requests = net::RateLimit::per_second_in_bursts_of_two(20);
  static constexpr std::size_t kBytesPerRequest = 64 * 1024;
  // A request (its line and headers) must arrive whole within this; a keep-alive connection with
  // no new request for this long is closed.
  std::chrono::milliseconds request_timeout{10'000};
  // [http] capture: /api/v1/capture is served (else 403); a capture's pcap stops at this size.
  bool capture = false;
  std::size_t capture_max_bytes = 16 * 1024 * 1024;
  // Captures streaming at once; one more is answered 503. A capture's connection has a slot of
  // its own, outside max_clients: captures never keep the status page out.
  std::size_t max_captures = 2;
};

struct HttpState;

class HttpServer {
 public:
  // Every timeout is measured on `clock` (net/clock.h), which must outlive the server.
  HttpServer(boost::asio::io_context& io, net::Clock& clock, Content& content, HttpOptions options,
             std::shared_ptr<spdlog::logger> log);
  ~HttpServer();  // close()
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  std::error_code listen();
  [[nodiscard]] std::uint16_t port() const;
  // Stops accepting and closes every connection.
  void close();
  [[nodiscard]] HttpStats stats() const;
  [[nodiscard]] std::size_t client_count() const;

 private:
  std::shared_ptr<HttpState> state_;
};

}  // namespace drivegate::http
