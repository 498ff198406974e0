// One HTTP client: reads a request (bounded: 8 KiB of headers, no body) within the request
// timeout, answers it from routes.h, and keeps the connection for the next one when the client
// asks to. A malformed or oversized request gets 400 or 431 and the connection closes.
#pragma once

#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/parser.hpp>
#include <boost/beast/http/string_body.hpp>
#include <memory>
#include <optional>

#include "http_state.h"

namespace drivegate::http {

class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(std::shared_ptr<HttpState> state, boost::asio::ip::tcp::socket socket);
  ~HttpConnection();
  void start();
  void close();

 private:
  void read();
  void on_read(const boost::system::error_code& ec);
  void reply(unsigned status, const std::string& content_type, std::string body, bool keep_alive,
             bool head, const std::string& allow = {});
  void on_written(const boost::system::error_code& ec, bool keep_alive);

  std::shared_ptr<HttpState> state_;
  boost::beast::tcp_stream stream_;
  boost::beast::flat_buffer buffer_;
  std::optional<boost::beast::http::request_parser<boost::beast::http::empty_body>> parser_;
  boost::beast::http::response<boost::beast::http::string_body> response_;
  std::string peer_;
  bool closed_ = false;
};

}  // namespace drivegate::http
