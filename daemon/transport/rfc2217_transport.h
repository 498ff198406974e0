// RFC 2217 over TCP: a Telnet connection to a serial device server (ser2net
// "telnet(rfc2217)", Moxa "RFC 2217" mode) on which drivegate itself sets the line: after the
// connection it negotiates BINARY and SUPPRESS-GO-AHEAD both ways and COM-PORT-OPTION, sends
// SET-BAUDRATE / DATASIZE / PARITY / STOPSIZE / CONTROL (no flow control), and is open only once
// the server has answered every setting with the value asked for. Data 0xFF is doubled on the
// wire both ways (telnet_codec.h).
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/steady_timer.hpp>
#include <deque>

#include "transport/tcp_transport.h"
#include "transport/telnet_codec.h"

namespace drivegate {

class Rfc2217Transport final : public Transport {
 public:
  // `log`: what the server answered when it differs from what was asked.
  Rfc2217Transport(boost::asio::io_context& io, const BusConfig& bus, std::string host,
                   std::uint16_t port, std::shared_ptr<spdlog::logger> log);
  void open(Done done) override;
  void read(Received received) override;
  void write(ByteView data, Done done) override;
  void close() override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] bool network() const override { return true; }

 private:
  void negotiate_more();
  void on_bytes(ByteView raw);
  void answer(const telnet::Event& e);
  void send_raw(Bytes bytes, Done done);
  void send_next();
  void finish_open(std::error_code ec);

  std::string bus_;
  std::shared_ptr<spdlog::logger> log_;
  TcpTransport tcp_;
  rfc2217::LineSettings asked_;
  telnet::Decoder decoder_;
  rfc2217::ServerSettings answered_;
  bool com_port_agreed_ = false;
  std::shared_ptr<Done> opening_;  // set while open() waits for the server's answers
  boost::asio::steady_timer open_timer_;
  Bytes data_;  // line data decoded from the last chunk
  std::vector<telnet::Event> events_;
  // Raw writes (data and negotiation replies) one at a time, in order.
  std::deque<std::pair<Bytes, Done>> queue_;
  bool writing_ = false;
  std::uint64_t generation_ = 0;  // close() makes completions of an earlier connection stale
};

}  // namespace drivegate
