// What the HTTP acceptor and its connections share; kept alive by every pending handler.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/ip/tcp.hpp>
#include <unordered_set>

#include "http_server.h"

namespace drivegate::http {

class HttpConnection;

struct HttpState {
  HttpState(boost::asio::io_context& io_, Content& content_, HttpOptions options_,
            std::shared_ptr<spdlog::logger> log_)
      : io(io_),
        content(content_),
        options(std::move(options_)),
        log(std::move(log_)),
        acceptor(io_) {}
  boost::asio::io_context& io;
  Content& content;
  const HttpOptions options;
  const std::shared_ptr<spdlog::logger> log;
  boost::asio::ip::tcp::acceptor acceptor;
  std::unordered_set<HttpConnection*> live;
  HttpStats stats;
  bool closed = false;
};

}  // namespace drivegate::http
