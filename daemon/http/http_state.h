// What the HTTP server's acceptor and connections share; kept alive by every pending handler.
#pragma once

#include <spdlog/logger.h>

#include <memory>
#include <unordered_set>

#include "http_server.h"
#include "net/acceptor.h"
#include "net/address_rate.h"
#include "net/clock.h"
#include "net/log_throttle.h"
#include "slice_renderer.h"

namespace drivegate::http {

class HttpConnection;

struct HttpState {
  HttpState(boost::asio::io_context& io_, net::Clock& clock_, Content& content_,
            HttpOptions options_, std::shared_ptr<spdlog::logger> log_)
      : io(io_),
        clock(clock_),
        content(content_),
        options(std::move(options_)),
        log(std::move(log_)),
        acceptor(std::make_shared<net::Acceptor>(io_, clock_, log, "http", options.allow)),
        request_rate(options.requests),
        slicer(std::make_shared<SliceRenderer>(io_.get_executor())) {}
  boost::asio::io_context& io;
  net::Clock& clock;  // every deadline of the server and its connections (net/clock.h)
  Content& content;
  const HttpOptions options;
  const std::shared_ptr<spdlog::logger> log;
  std::shared_ptr<net::Acceptor> acceptor;
  std::unordered_set<HttpConnection*> live;
  std::size_t capturing = 0;      // of `live`, the connections streaming a capture
  net::AddressRate request_rate;  // options.requests, per client address
  std::shared_ptr<SliceRenderer> slicer;  // documents made a slice at a time (/api/v1/events)
  HttpStats stats;  // its own counts; the acceptor's (accepted, not allowed, refused) are its
  net::LogThrottle bad_request_log;  // any client can cause one: a burst, then one a second
  net::LogThrottle paced_log;        // requests held back by the rate limit
  bool closed = false;
};

}  // namespace drivegate::http
