#include "http_connection.h"

#include <spdlog/spdlog.h>

#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/http/chunk_encode.hpp>
#include <boost/beast/http/error.hpp>
#include <boost/beast/http/read.hpp>
#include <boost/beast/http/write.hpp>

#include "routes.h"

namespace drivegate::http {

namespace bhttp = boost::beast::http;

namespace {
// Request line and headers together; a status page or a scraper sends a few hundred bytes.
constexpr std::uint32_t kHeaderLimit = 8 * 1024;
}  // namespace

HttpConnection::HttpConnection(std::shared_ptr<HttpState> state,
                               boost::asio::ip::tcp::socket socket)
    : state_(std::move(state)),
      stream_(std::move(socket)),
      buffer_(kHeaderLimit),
      deadline_(stream_.get_executor(), state_->clock),
      pace_timer_(stream_.get_executor(), state_->clock),
      capture_timer_(stream_.get_executor(), state_->clock) {}

HttpConnection::~HttpConnection() {
  close();
}

void HttpConnection::start() {
  boost::system::error_code ec;
  const auto peer = stream_.socket().remote_endpoint(ec);
  address_ = peer.address();
  peer_ = address_.to_string() + ":" + std::to_string(peer.port());
  // Without it, Nagle holds each write slice after the first until the client ACKs the one before,
  // and a client that delays its ACKs (Linux: 40 ms) gets a kept-alive document that late.
  stream_.socket().set_option(boost::asio::ip::tcp::no_delay(true), ec);
  state_->live.insert(this);  // the acceptor counted it in
  read();
}

void HttpConnection::close() {
  if (closed_) return;
  closed_ = true;
  deadline_.cancel();
  pace_timer_.cancel();
  capture_timer_.cancel();
  if (capturing_) {
    capturing_ = false;
    --state_->capturing;
  }
  capture_.reset();  // removes the tap from the bus
  boost::system::error_code ec;
  stream_.socket().shutdown(boost::asio::ip::tcp::socket::shutdown_both, ec);
  stream_.socket().close(ec);
  if (state_->live.erase(this) != 0) state_->acceptor->left();
}

// One deadline for the operation in flight: a whole request to arrive, or the client to take what
// it is sent; past it the connection closes. Each completion cancels it: nothing is due while
// the server itself holds the connection (a paced request, a capture waiting for frames).
void HttpConnection::within_timeout(bool awaiting_request) {
  awaiting_request_ = awaiting_request;
  deadline_.expires_after(state_->options.request_timeout);
  deadline_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || self->closed_) return;
    if (self->awaiting_request_) {
      ++self->state_->stats.timeouts;
      self->state_->log->debug("http: client {}: no whole request in {} ms, closing", self->peer_,
                               self->state_->options.request_timeout.count());
    }
    self->close();
  });
}

void HttpConnection::read() {
  parser_.emplace();
  parser_->header_limit(kHeaderLimit);
  parser_->body_limit(0);  // GET and HEAD carry no body: one that does is refused
  within_timeout(true);
  header_bytes_ = 0;
  read_header();
}

// The header only: a request announcing a body (Content-Length or chunked) is refused before a
// byte of the body is parsed. Beast 1.74's chunk parser asserts on a final chunk that arrives a
// byte at a time (fatal where assertions are on: Debug builds, and Debian's
// CMAKE_BUILD_TYPE=None), and a GET has nothing to send anyway.
// Read a part at a time, counting what the parser consumed: Beast checks header_limit only
// against what is buffered at each step, so field lines consumed by an earlier step were not
// counted, and headers arriving in two reads of ~8 KiB on a kept connection passed whole.
void HttpConnection::read_header() {
  bhttp::async_read_some(
      stream_, buffer_, *parser_,
      [self = shared_from_this()](const boost::system::error_code& ec, std::size_t consumed) {
        if (ec) {
          self->on_read(ec);
          return;
        }
        self->header_bytes_ += consumed;
        if (self->header_bytes_ > kHeaderLimit) {
          self->on_read(bhttp::error::header_limit);
          return;
        }
        if (!self->parser_->is_header_done()) {
          self->read_header();
          return;
        }
        self->on_read(self->parser_->is_done() ? boost::system::error_code{}
                                               : bhttp::error::unexpected_body);
      });
}

void HttpConnection::on_read(const boost::system::error_code& ec) {
  if (closed_) return;
  deadline_.cancel();  // a paced request waits without one: it is the server that holds it
  if (ec == bhttp::error::end_of_stream || ec == boost::asio::error::eof ||
      ec == boost::asio::error::connection_reset) {
    close();
    return;
  }
  if (ec) {
    ++state_->stats.bad_requests;
    if (const auto held = state_->bad_request_log.admit(state_->clock.now())) {
      state_->log->info("http: client {}: bad request ({}), closing{}", peer_, ec.message(),
                        net::held_note(*held));
    }
    const bool too_large = ec == bhttp::error::header_limit || ec == bhttp::error::buffer_overflow;
    reply(too_large ? 431 : 400, "text/plain; charset=utf-8",
          too_large ? "request headers too large\n" : "bad request\n", false, false);
    return;
  }
  serve();
}

void HttpConnection::serve() {
  if (closed_) return;
  const auto now = state_->clock.now();
  if (!state_->request_rate.admit(address_, now)) {
    // Over its share: the request waits for the address's next token and nothing more is read
    // from this connection meanwhile, so a hammering client slows itself down (TCP's window
    // fills), never the loop. Another client's requests are not held up.
    ++state_->stats.requests_paced;
    if (const auto held = state_->paced_log.admit(now)) {
      state_->log->info("http: client {}: over {} requests a second, answers paced{}", peer_,
                        state_->options.requests.per_second, net::held_note(*held));
    }
    pace_timer_.expires_at(state_->request_rate.next_token(address_, now));
    pace_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (!ec) self->serve();
    });
    return;
  }
  answer();
}

void HttpConnection::answer() {
  ++state_->stats.requests;
  const auto& request = parser_->get();
  Response r =
      route(std::string_view(request.method_string().data(), request.method_string().size()),
            std::string_view(request.target().data(), request.target().size()), state_->content,
            RouteOptions{state_->options.capture});
  if (r.capture && request.method() == bhttp::verb::get) {
    serve_capture(*r.capture);
    return;
  }
  const bool head = request.method() == bhttp::verb::head;
  if (r.sliced) {
    // Nothing is read from the connection until the document is whole and answered.
    state_->slicer->render(
        std::move(r.sliced),
        [self = shared_from_this(), status = r.status, type = r.content_type,
         keep_alive = request.keep_alive(), head](std::shared_ptr<const std::string> document) {
          if (!self->closed_) {
            self->reply(status, type, std::move(document), keep_alive, head);
          }
        });
    return;
  }
  reply(r.status, r.content_type, std::move(r.body), request.keep_alive(), head, r.allow);
}

void HttpConnection::reply(unsigned status, const std::string& content_type, std::string body,
                           bool keep_alive, bool head, const std::string& allow,
                           unsigned retry_after_s) {
  reply(status, content_type, std::make_shared<const std::string>(std::move(body)), keep_alive,
        head, allow, retry_after_s);
}

void HttpConnection::reply(unsigned status, const std::string& content_type,
                           std::shared_ptr<const std::string> body, bool keep_alive, bool head,
                           const std::string& allow, unsigned retry_after_s) {
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
  if (retry_after_s > 0) response_.set(bhttp::field::retry_after, std::to_string(retry_after_s));
  response_.keep_alive(keep_alive);
  body_ = std::move(body);
  const std::size_t size = body_->size();
  // A large response counts as the requests its size is worth (HttpOptions::requests): the
  // address's next request waits for them, so the bytes one address pulls a second are bounded.
  if (const std::size_t more = size / HttpOptions::kBytesPerRequest; more > 0) {
    state_->request_rate.charge(address_, static_cast<double>(more), state_->clock.now());
  }
  if (!head) response_.body() = {body_->data(), size};
  response_.content_length(size);
  within_timeout(false);  // a client that does not read
  response_writer_.emplace(response_);
  response_writer_->limit(kSliceBytes);
  bhttp::async_write(
      stream_, *response_writer_,
      [self = shared_from_this(), keep_alive](const boost::system::error_code& ec, std::size_t) {
        self->on_written(ec, keep_alive);
      });
}

void HttpConnection::on_written(const boost::system::error_code& ec, bool keep_alive) {
  if (closed_) return;
  deadline_.cancel();
  if (ec || !keep_alive) {
    close();
    return;
  }
  read();
}

// --- the capture stream ---

void HttpConnection::serve_capture(const CaptureRequest& request) {
  if (state_->capturing >= state_->options.max_captures) {
    ++state_->stats.captures_refused;
    state_->log->info("http: client {}: capture of bus {} refused: {} running already", peer_,
                      request.bus, state_->capturing);
    reply(503, "text/plain; charset=utf-8",
          std::to_string(state_->options.max_captures) +
              " captures are running already; try again when one has ended\n",
          false, false, {}, 10);
    return;
  }
  std::weak_ptr<HttpConnection> weak = weak_from_this();
  capture_ = state_->content.start_capture(request.bus, state_->options.capture_max_bytes, [weak] {
    if (auto self = weak.lock()) self->capture_data();
  });
  if (!capture_) {  // the bus went in a reload between route() and now
    reply(404, "text/plain; charset=utf-8", "no such bus\n", false, false);
    return;
  }
  ++state_->stats.captures;
  // From here on its slot is a capture's (HttpOptions::max_captures), no longer one of
  // max_clients.
  capturing_ = true;
  ++state_->capturing;
  capture_bus_ = request.bus;
  state_->log->info("http: client {}: capture of bus {} for {} s", peer_, request.bus,
                    request.duration.count());
  stream_head_ = {};
  stream_head_.version(11);
  stream_head_.result(bhttp::status::ok);
  stream_head_.set(bhttp::field::server, "drivegate");
  stream_head_.set(bhttp::field::content_type, "application/vnd.tcpdump.pcap");
  stream_head_.set(bhttp::field::cache_control, "no-store");
  std::string file = request.bus;  // a configured name, but a header is no place for quotes
  for (char& c : file) {
    if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = '_';
  }
  stream_head_.set(bhttp::field::content_disposition, "attachment; filename=\"" + file + ".pcap\"");
  stream_head_.set("X-Content-Type-Options", "nosniff");
  stream_head_.keep_alive(false);
  stream_head_.chunked(true);
  serializer_.emplace(stream_head_);
  capture_writing_ = true;
  within_timeout(false);
  bhttp::async_write_header(
      stream_, *serializer_,
      [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
        self->capture_writing_ = false;
        self->deadline_.cancel();
        if (ec) {
          self->close();
          return;
        }
        self->pump_capture();
      });
  capture_timer_.expires_after(request.duration);
  capture_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || self->closed_) return;
    self->capture_ending_ = true;
    self->pump_capture();
  });
  watch_peer();
}

// Called from inside the bus's handling of a frame: only schedules the write.
void HttpConnection::capture_data() {
  if (closed_ || capture_posted_) return;
  capture_posted_ = true;
  boost::asio::post(stream_.get_executor(), [self = shared_from_this()] {
    self->capture_posted_ = false;
    self->pump_capture();
  });
}

void HttpConnection::pump_capture() {
  if (closed_ || capture_writing_ || capture_done_) return;
  std::string data = capture_ ? capture_->take() : std::string();
  if (capture_ && capture_->full()) capture_ending_ = true;
  if (!data.empty()) {
    chunk_ = std::move(data);
    capture_writing_ = true;
    within_timeout(false);  // a client that does not read
    boost::asio::async_write(
        stream_, bhttp::make_chunk(boost::asio::buffer(chunk_)),
        [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
          self->capture_writing_ = false;
          self->deadline_.cancel();  // between chunks the stream waits on the bus, not the client
          if (ec) {
            self->state_->log->debug("http: client {}: capture stream: {}", self->peer_,
                                     ec.message());
            self->close();
            return;
          }
          self->pump_capture();
        });
    return;
  }
  if (!capture_ending_) return;
  capture_done_ = true;
  capture_timer_.cancel();
  capture_.reset();  // the tap goes now; what it held has been written
  state_->log->info("http: client {}: capture of bus {} done", peer_, capture_bus_);
  within_timeout(false);
  boost::asio::async_write(stream_, bhttp::make_chunk_last(),
                           [self = shared_from_this()](const boost::system::error_code&,
                                                       std::size_t) { self->close(); });
}

// The client sends nothing more; a read that ends means it went away: the capture ends with it.
void HttpConnection::watch_peer() {
  stream_.socket().async_read_some(
      boost::asio::buffer(probe_),
      [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
        if (self->closed_) return;
        if (ec) {
          self->state_->log->debug("http: client {}: left during the capture of bus {}",
                                   self->peer_, self->capture_bus_);
          self->close();
          return;
        }
        self->watch_peer();
      });
}

}  // namespace drivegate::http
