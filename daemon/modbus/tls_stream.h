// Modbus/TCP Security after the handshake: TLS records read and written on the event loop with
// OpenSSL's SSL_read_ex / SSL_write_ex straight on the connection's socket (a BIO of our own over
// the file descriptor), waiting with the socket's async_wait whenever OpenSSL wants to read or
// write. The handshake itself runs on the server's handshake thread (handshaker.h), which hands
// the SSL* over when it is done: asio::ssl::stream (Boost 1.74) cannot adopt an SSL* handshaken
// elsewhere, and its BIO pair copies every record once more than this does.
//
// One operation of each kind at a time (one read, one write), both on the event loop. A
// handler is never called from inside the call that started it: an operation that completes at
// once is posted to the socket's executor.
#pragma once

#include <boost/asio/buffer.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/system/error_code.hpp>
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>

using SSL = struct ssl_st;
using SSL_CTX = struct ssl_ctx_st;

namespace drivegate::modbus {

struct SslFree {
  void operator()(SSL* ssl) const;
};
using SslPtr = std::unique_ptr<SSL, SslFree>;

// A server-side SSL* of `context` that reads and writes the connected, non-blocking socket `fd`
// itself (recv, and send with MSG_NOSIGNAL: a client gone is an error, never SIGPIPE), in accept
// state. It does not own `fd`. nullptr when OpenSSL cannot allocate one.
SslPtr new_socket_ssl(SSL_CTX* context, int fd);

// What an SSL_* call that returned `result` (not success) means: the socket state to wait for
// (read or write), or the error that ends the stream (eof for a close_notify, stream_truncated
// for a peer gone without one, the system's or OpenSSL's error otherwise). Call it at once, on
// the thread that made the call: OpenSSL's error queue and errno are that thread's.
std::optional<boost::asio::socket_base::wait_type> ssl_wait(SSL* ssl, int result,
                                                            boost::system::error_code& error);

class TlsStream {
 public:
  using Handler = std::function<void(const boost::system::error_code&, std::size_t)>;

  // `socket` (the connection's, which outlives the stream) carries `ssl`, handshaken. From here
  // the end of the client's stream reads as eof, with or without close_notify.
  TlsStream(boost::asio::ip::tcp::socket& socket, SslPtr ssl);

  [[nodiscard]] SSL* native_handle() const { return ssl_.get(); }
  // Up to `buffer.size()` bytes of application data, at least one unless an error is reported.
  void async_read_some(boost::asio::mutable_buffer buffer, Handler handler);
  // All of `buffer` (which must stay put until the handler runs), or an error.
  void async_write(boost::asio::const_buffer buffer, Handler handler);

 private:
  void write_from(boost::asio::const_buffer buffer, std::size_t done, Handler handler);
  void complete(Handler handler, const boost::system::error_code& error, std::size_t n);

  boost::asio::ip::tcp::socket& socket_;
  SslPtr ssl_;
};

}  // namespace drivegate::modbus
