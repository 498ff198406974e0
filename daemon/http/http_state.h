// What the HTTP acceptor and its connections share; kept alive by every pending handler.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <unordered_set>

#include "http_server.h"
#include "net/address_rate.h"
#include "net/log_throttle.h"

namespace drivegate::http {

class HttpConnection;

struct HttpState {
  HttpState(boost::asio::io_context& io_, Content& content_, HttpOptions options_,
            std::shared_ptr<spdlog::logger> log_)
      : io(io_),
        content(content_),
        options(std::move(options_)),
        log(std::move(log_)),
        acceptor(io_),
        retry_timer(io_),
        request_rate(options.requests) {}
  boost::asio::io_context& io;
  Content& content;
  const HttpOptions options;
  const std::shared_ptr<spdlog::logger> log;
  boost::asio::ip::tcp::acceptor acceptor;
  boost::asio::steady_timer retry_timer;  // accept back-off after EMFILE and the like
  std::unordered_set<HttpConnection*> live;
  std::size_t capturing = 0;         // of `live`, the connections streaming a capture
  net::AddressRate request_rate;  // options.requests, per client address
  HttpStats stats;
  net::LogThrottle bad_request_log;   // any client can cause one: a burst, then one a second
  net::LogThrottle accept_error_log;  // accept() failing (out of descriptors and the like)
  net::LogThrottle paced_log;         // requests held back by the rate limit
  bool closed = false;
};

}  // namespace drivegate::http
