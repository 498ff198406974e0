#include "http_connection.h"

#include <spdlog/spdlog.h>

#include <boost/beast/http/read.hpp>
#include <boost/beast/http/write.hpp>

#include "routes.h"

namespace drivegate::http {

namespace beast = boost::beast;
namespace bhttp = boost::beast::http;

namespace {
// Request line and headers together; a status page or a scraper sends a few hundred bytes.
constexpr std::uint32_t kHeaderLimit = 8 * 1024;
}  // namespace

HttpConnection::HttpConnection(std::shared_ptr<HttpState> state,
                               boost::asio::ip::tcp::socket socket)
    : state_(std::move(state)), stream_(std::move(socket)), buffer_(kHeaderLimit) {}

HttpConnection::~HttpConnection() {
  close();
}

void HttpConnection::start() {
  boost::system::error_code ec;
  const auto peer = stream_.socket().remote_endpoint(ec);
  peer_ = peer.address().to_string() + ":" + std::to_string(peer.port());
  state_->live.insert(this);
  ++state_->stats.accepted;
  read();
}

void HttpConnection::close() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ec;
  stream_.socket().shutdown(boost::asio::ip::tcp::socket::shutdown_both, ec);
  stream_.socket().close(ec);
  state_->live.erase(this);
}

void HttpConnection::read() {
  parser_.emplace();
  parser_->header_limit(kHeaderLimit);
  parser_->body_limit(0);  // GET and HEAD carry no body: one that does is refused
  stream_.expires_after(state_->options.request_timeout);
  bhttp::async_read(stream_, buffer_, *parser_,
                    [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
                      self->on_read(ec);
                    });
}

void HttpConnection::on_read(const boost::system::error_code& ec) {
  if (closed_) return;
  if (ec == bhttp::error::end_of_stream || ec == boost::asio::error::eof ||
      ec == boost::asio::error::connection_reset) {
    close();
    return;
  }
  if (ec == beast::error::timeout) {
    ++state_->stats.timeouts;
    state_->log->debug("http: client {}: no whole request in {} ms, closing", peer_,
                       state_->options.request_timeout.count());
    close();
    return;
  }
  if (ec) {
    ++state_->stats.bad_requests;
    state_->log->info("http: client {}: bad request ({}), closing", peer_, ec.message());
    const bool too_large = ec == bhttp::error::header_limit || ec == bhttp::error::buffer_overflow;
    reply(too_large ? 431 : 400, "text/plain; charset=utf-8",
          too_large ? "request headers too large\n" : "bad request\n", false, false);
    return;
  }
  ++state_->stats.requests;
  const auto& request = parser_->get();
  const Response r = route(std::string_view(request.method_string().data(),
                                            request.method_string().size()),
                           std::string_view(request.target().data(), request.target().size()),
                           state_->content);
  reply(r.status, r.content_type, r.body, request.keep_alive(),
        request.method() == bhttp::verb::head, r.allow);
}

void HttpConnection::reply(unsigned status, const std::string& content_type, std::string body,
                           bool keep_alive, bool head, const std::string& allow) {
  response_ = {};
  response_.version(11);
  response_.result(status);
  response_.set(bhttp::field::server, "drivegate");
  response_.set(bhttp::field::content_type, content_type);
  response_.set(bhttp::field::cache_control, "no-store");
  // The page's script and style are inline; nothing may be loaded from anywhere else.
  response_.set("Content-Security-Policy",
                "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
                "connect-src 'self'; img-src 'self' data:");
  response_.set("X-Content-Type-Options", "nosniff");
  if (!allow.empty()) response_.set(bhttp::field::allow, allow);
  response_.keep_alive(keep_alive);
  const std::size_t size = body.size();
  if (!head) response_.body() = std::move(body);
  response_.content_length(size);
  stream_.expires_after(state_->options.request_timeout);  // a client that does not read
  bhttp::async_write(stream_, response_,
                     [self = shared_from_this(), keep_alive](const boost::system::error_code& ec,
                                                             std::size_t) {
                       self->on_written(ec, keep_alive);
                     });
}

void HttpConnection::on_written(const boost::system::error_code& ec, bool keep_alive) {
  if (closed_) return;
  if (ec || !keep_alive) {
    close();
    return;
  }
  read();
}

}  // namespace drivegate::http
