// A raw TCP connection to a serial device server (ser2net "tcp", Moxa NPort "TCP server" mode):
// the bytes on the socket are the bytes on the line. The line settings are the server's own.
// What TCP cannot keep: the inter-frame gap is measured here, not on the far wire (a frame may
// leave the server later than it left us, two frames may be sent back to back by a server that
// buffered both), and replies arrive with the network's delay on top (network_delay_ms).
#pragma once

#include <boost/asio/ip/tcp.hpp>

#include "transport/transport.h"

namespace drivegate {

class TcpTransport final : public Transport {
 public:
  TcpTransport(boost::asio::io_context& io, std::string host, std::uint16_t port);
  void open(Done done) override;
  void read(Received received) override;
  void write(ByteView data, Done done) override;
  void close() override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool network() const override { return true; }

  // For RFC 2217, which writes its own (already escaped) bytes.
  void write_raw(Bytes bytes, Done done);
  // "host:port" ("[v6]:port"), as describe() and RFC 2217's describe() name the server.
  [[nodiscard]] std::string endpoint() const;

 private:
  std::string host_;
  std::uint16_t port_;
  boost::asio::ip::tcp::resolver resolver_;
  boost::asio::ip::tcp::socket socket_;
  std::array<std::uint8_t, 512> chunk_{};
  Bytes tx_;
};

}  // namespace drivegate
