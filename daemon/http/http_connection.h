// One HTTP client: reads a request (bounded: 8 KiB of headers, no body) within the request
// timeout, answers it from routes.h, and keeps the connection for the next one when the client
// asks to. A malformed or oversized request gets 400 or 431 and the connection closes.
// /api/v1/capture is served as a stream: a chunked pcap for the request's duration (or until the
// size cap), fed by a tap on the bus, after which the connection closes; a client that goes away
// ends the capture and its tap.
#pragma once

#include <array>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/http/empty_body.hpp>
#include <boost/beast/http/parser.hpp>
#include <boost/beast/http/serializer.hpp>
#include <boost/beast/http/span_body.hpp>
#include <memory>
#include <optional>

#include "http_state.h"
#include "net/clock.h"
#include "routes.h"

namespace drivegate::http {

class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(std::shared_ptr<HttpState> state, boost::asio::ip::tcp::socket socket);
  ~HttpConnection();
  void start();
  void close();

 private:
  void within_timeout(bool awaiting_request);
  void read();
  void read_header();
  void on_read(const boost::system::error_code& ec);
  // Answers the parsed request, or, when its address has used its share of requests for now,
  // waits for its next one first (HttpOptions::requests).
  void serve();
  void answer();
  void reply(unsigned status, const std::string& content_type, std::string body, bool keep_alive,
             bool head, const std::string& allow = {}, unsigned retry_after_s = 0);
  // The same for a body kept elsewhere too (a page many requests share): not copied.
  void reply(unsigned status, const std::string& content_type,
             std::shared_ptr<const std::string> body, bool keep_alive, bool head,
             const std::string& allow = {}, unsigned retry_after_s = 0);
  void on_written(const boost::system::error_code& ec, bool keep_alive);
  // The capture stream: headers, then a chunk per batch of frames, then the last chunk.
  void serve_capture(const CaptureRequest& request);
  void capture_data();
  void pump_capture();
  void watch_peer();

  std::shared_ptr<HttpState> state_;
  boost::beast::tcp_stream stream_;
  boost::beast::flat_buffer buffer_;
  std::optional<boost::beast::http::request_parser<boost::beast::http::empty_body>> parser_;
  std::size_t header_bytes_ = 0;  // of the request being read, as the parser consumed them
  // The response: its body is a view of body_, which may be shared with other requests.
  using Body = boost::beast::http::span_body<const char>;
  boost::beast::http::response<Body> response_;
  std::shared_ptr<const std::string> body_;
  // Writes response_ a slice at a time (kSliceBytes): between slices the event loop runs what
  // else is ready, Modbus requests first among them, instead of waiting for one long send.
  std::optional<boost::beast::http::response_serializer<Body>> response_writer_;
  std::string peer_;
  boost::asio::ip::address address_;  // the client's, for the request rate
  net::Timer deadline_;  // request_timeout: for a whole request, or for the client to read
  bool awaiting_request_ = false;  // what deadline_ waits for is a request (counted `timeouts`)
  net::Timer pace_timer_;          // a request waiting for its turn
  bool closed_ = false;
  bool capturing_ = false;  // counted in HttpState::capturing

  std::unique_ptr<CaptureStream> capture_;
  std::string capture_bus_;
  boost::beast::http::response<boost::beast::http::empty_body> stream_head_;
  std::optional<boost::beast::http::response_serializer<boost::beast::http::empty_body>>
      serializer_;
  net::Timer capture_timer_;
  std::string chunk_;              // being written
  bool capture_writing_ = false;   // a write is in flight
  bool capture_posted_ = false;    // pump_capture() is posted
  bool capture_ending_ = false;    // duration over, cap reached or bus gone: finish
  bool capture_done_ = false;      // the last chunk is written or being written
  std::array<char, 256> probe_{};  // what a streaming client sends (nothing, or its close)
};

}  // namespace drivegate::http
