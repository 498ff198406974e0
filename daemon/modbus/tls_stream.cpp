#include "tls_stream.h"

#include <openssl/bio.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <sys/socket.h>

#include <boost/asio/error.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl/error.hpp>
#include <cerrno>
#include <cstdint>
#include <utility>

namespace drivegate::modbus {
namespace {

namespace asio = boost::asio;

int fd_of(BIO* bio) {
  return static_cast<int>(reinterpret_cast<std::intptr_t>(BIO_get_data(bio)));
}

bool try_again(int error) {
  return error == EAGAIN || error == EWOULDBLOCK || error == EINTR;
}

int socket_write(BIO* bio, const char* data, int size) {
  BIO_clear_retry_flags(bio);
  const ssize_t n = ::send(fd_of(bio), data, static_cast<std::size_t>(size), MSG_NOSIGNAL);
  if (n >= 0) return static_cast<int>(n);
  if (try_again(errno)) BIO_set_retry_write(bio);
  return -1;
}

int socket_read(BIO* bio, char* data, int size) {
  BIO_clear_retry_flags(bio);
  const ssize_t n = ::recv(fd_of(bio), data, static_cast<std::size_t>(size), 0);
  if (n > 0) return static_cast<int>(n);
  if (n == 0) {
    // OpenSSL asks BIO_eof() to tell a peer gone without close_notify from an error.
    BIO_set_flags(bio, BIO_FLAGS_IN_EOF);
    return 0;
  }
  if (try_again(errno)) BIO_set_retry_read(bio);
  return -1;
}

long socket_ctrl(BIO* bio, int command, long, void*) {
  switch (command) {
    case BIO_CTRL_FLUSH:
      return 1;  // nothing is buffered here
    case BIO_CTRL_EOF:
      return BIO_test_flags(bio, BIO_FLAGS_IN_EOF) != 0 ? 1 : 0;
    default:
      return 0;
  }
}

int socket_create(BIO* bio) {
  BIO_set_init(bio, 1);
  return 1;
}

// The method table of the socket BIO: built once, read-only after, shared by every SSL* (it must
// outlive them all, so it is never freed). BIO_s_socket is not used: it writes with write(2),
// and a client that closed would raise SIGPIPE in the daemon.
const BIO_METHOD* socket_method() {
  static const BIO_METHOD* const method = [] {
    BIO_METHOD* m = BIO_meth_new(BIO_get_new_index() | BIO_TYPE_SOURCE_SINK, "drivegate socket");
    if (m == nullptr) return m;
    BIO_meth_set_write(m, socket_write);
    BIO_meth_set_read(m, socket_read);
    BIO_meth_set_ctrl(m, socket_ctrl);
    BIO_meth_set_create(m, socket_create);
    return m;
  }();
  return method;
}

}  // namespace

void SslFree::operator()(SSL* ssl) const {
  SSL_free(ssl);
}

SslPtr new_socket_ssl(SSL_CTX* context, int fd) {
  const BIO_METHOD* method = socket_method();
  if (method == nullptr) return nullptr;
  SslPtr ssl(SSL_new(context));
  if (!ssl) return nullptr;
  BIO* bio = BIO_new(method);
  if (bio == nullptr) return nullptr;
  // The BIO's data is the socket's descriptor itself, not a pointer (socket_method() reads it).
  // NOLINTNEXTLINE(performance-no-int-to-ptr)
  BIO_set_data(bio, reinterpret_cast<void*>(static_cast<std::intptr_t>(fd)));
  SSL_set_bio(ssl.get(), bio, bio);  // the SSL owns the BIO (one reference for both ends)
  // A write retried after WANT_WRITE passes the rest of the same buffer.
  SSL_set_mode(ssl.get(), SSL_MODE_ACCEPT_MOVING_WRITE_BUFFER);
  SSL_set_accept_state(ssl.get());
  return ssl;
}

std::optional<asio::socket_base::wait_type> ssl_wait(SSL* ssl, int result,
                                                     boost::system::error_code& error) {
  const int saved_errno = errno;
  switch (SSL_get_error(ssl, result)) {
    case SSL_ERROR_WANT_READ:
      return asio::socket_base::wait_read;
    case SSL_ERROR_WANT_WRITE:
      return asio::socket_base::wait_write;
    case SSL_ERROR_ZERO_RETURN:
      error = asio::error::eof;  // close_notify
      return std::nullopt;
    case SSL_ERROR_SYSCALL:
      if (ERR_peek_error() == 0) {
        error = saved_errno != 0
                    ? boost::system::error_code(saved_errno, boost::system::system_category())
                    : boost::system::error_code(asio::ssl::error::stream_truncated);
        return std::nullopt;
      }
      break;
    default:
      break;
  }
  const unsigned long e = ERR_get_error();
  if (e == 0 || ERR_GET_REASON(e) == SSL_R_UNEXPECTED_EOF_WHILE_READING) {
    error = asio::ssl::error::stream_truncated;  // the peer closed without close_notify
  } else {
    error = boost::system::error_code(static_cast<int>(e), asio::error::get_ssl_category());
  }
  ERR_clear_error();
  return std::nullopt;
}

TlsStream::TlsStream(asio::ip::tcp::socket& socket, SslPtr ssl)
    : socket_(socket), ssl_(std::move(ssl)) {
  // A client that shuts its side down without close_notify has sent all it will, as one that
  // sends close_notify has: its requests are still answered (connection.h). Without this option
  // OpenSSL 3 makes that EOF a fatal error and refuses the replies. MBAP frames carry their own
  // length, so a truncated stream is only an unfinished frame, never a short request taken whole.
  SSL_set_options(ssl_.get(), SSL_OP_IGNORE_UNEXPECTED_EOF);
}

void TlsStream::complete(Handler handler, const boost::system::error_code& error, std::size_t n) {
  asio::post(socket_.get_executor(),
             [handler = std::move(handler), error, n] { handler(error, n); });
}

void TlsStream::async_read_some(asio::mutable_buffer buffer, Handler handler) {
  ERR_clear_error();
  errno = 0;
  std::size_t n = 0;
  const int r = SSL_read_ex(ssl_.get(), buffer.data(), buffer.size(), &n);
  if (r == 1) return complete(std::move(handler), {}, n);
  boost::system::error_code error;
  const auto wait = ssl_wait(ssl_.get(), r, error);
  if (!wait) return complete(std::move(handler), error, 0);
  socket_.async_wait(*wait, [this, buffer, handler = std::move(handler)](
                                const boost::system::error_code& ec) mutable {
    if (ec) return handler(ec, 0);
    async_read_some(buffer, std::move(handler));
  });
}

void TlsStream::async_write(asio::const_buffer buffer, Handler handler) {
  write_from(buffer, 0, std::move(handler));
}

void TlsStream::write_from(asio::const_buffer buffer, std::size_t done, Handler handler) {
  while (done < buffer.size()) {
    ERR_clear_error();
    errno = 0;
    std::size_t n = 0;
    const int r = SSL_write_ex(ssl_.get(), static_cast<const std::uint8_t*>(buffer.data()) + done,
                               buffer.size() - done, &n);
    if (r == 1) {
      done += n;
      continue;
    }
    boost::system::error_code error;
    const auto wait = ssl_wait(ssl_.get(), r, error);
    if (!wait) return complete(std::move(handler), error, done);
    socket_.async_wait(*wait, [this, buffer, done, handler = std::move(handler)](
                                  const boost::system::error_code& ec) mutable {
      if (ec) return handler(ec, done);
      write_from(buffer, done, std::move(handler));
    });
    return;
  }
  complete(std::move(handler), {}, done);
}

}  // namespace drivegate::modbus
