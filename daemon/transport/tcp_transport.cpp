#include "transport/tcp_transport.h"

#include <netinet/in.h>
#include <netinet/tcp.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/write.hpp>

namespace drivegate {

namespace asio = boost::asio;
using asio::ip::tcp;

namespace {

// A device server that loses power or its network leaves our socket open and silent: TCP
// keep-alive probes it after 5 s without traffic and gives up after 3 unanswered probes 2 s
// apart, so a dead peer is noticed in ~11 s even when no frame is in flight.
void keep_alive(tcp::socket& s) {
  boost::system::error_code ignored;
  s.set_option(asio::socket_base::keep_alive(true), ignored);
  const int idle = 5;
  const int interval = 2;
  const int count = 3;
  ::setsockopt(s.native_handle(), IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle);
  ::setsockopt(s.native_handle(), IPPROTO_TCP, TCP_KEEPINTVL, &interval, sizeof interval);
  ::setsockopt(s.native_handle(), IPPROTO_TCP, TCP_KEEPCNT, &count, sizeof count);
  s.set_option(tcp::no_delay(true), ignored);  // a frame leaves as one segment, at once
}

}  // namespace

TcpTransport::TcpTransport(asio::io_context& io, std::string host, std::uint16_t port)
    : host_(std::move(host)), port_(port), resolver_(io), socket_(io) {}

void TcpTransport::open(Done done) {
  // Name resolution is asynchronous (Asio runs getaddrinfo off the event loop), so a slow DNS
  // server never stalls the other buses or the Modbus clients.
  resolver_.async_resolve(
      host_, std::to_string(port_),
      [this, done = std::move(done)](const boost::system::error_code& ec,
                                     const tcp::resolver::results_type& results) mutable {
        if (ec) {
          done(from_asio(ec));
          return;
        }
        asio::async_connect(socket_, results,
                            [this, done = std::move(done)](const boost::system::error_code& e,
                                                           const tcp::endpoint&) {
                              if (!e) keep_alive(socket_);
                              done(from_asio(e));
                            });
      });
}

void TcpTransport::read(Received received) {
  socket_.async_read_some(
      asio::buffer(chunk_),
      [this, received = std::move(received)](const boost::system::error_code& ec, std::size_t n) {
        received(from_asio(ec), ByteView(chunk_.data(), ec ? 0 : n));
      });
}

void TcpTransport::write(ByteView data, Done done) {
  write_raw(Bytes(data.begin(), data.end()), std::move(done));
}

void TcpTransport::write_raw(Bytes bytes, Done done) {
  tx_ = std::move(bytes);
  asio::async_write(socket_, asio::buffer(tx_),
                    [done = std::move(done)](const boost::system::error_code& ec, std::size_t) {
                      done(from_asio(ec));
                    });
}

void TcpTransport::close() {
  resolver_.cancel();
  boost::system::error_code ignored;
  socket_.shutdown(tcp::socket::shutdown_both, ignored);
  socket_.close(ignored);
}

std::string TcpTransport::endpoint() const {
  const bool v6 = host_.find(':') != std::string::npos;
  return (v6 ? "[" + host_ + "]" : host_) + ":" + std::to_string(port_);
}

std::string TcpTransport::describe() const {
  return "tcp " + endpoint();
}

}  // namespace drivegate
