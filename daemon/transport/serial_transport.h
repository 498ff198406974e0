// A local serial port (tty): opened and configured by open_serial (serial_line.h).
#pragma once

#include <boost/asio/serial_port.hpp>

#include "transport/port_lock.h"
#include "transport/transport.h"

namespace drivegate {

class SerialTransport final : public Transport {
 public:
  SerialTransport(boost::asio::io_context& io, BusConfig bus);
  void open(Done done) override;
  void read(Received received) override;
  void write(ByteView data, Done done) override;
  void close() override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string explain(std::error_code ec) const override;
  // A stale lock it could not remove, and the settings the port did not take (serial_line.h).
  [[nodiscard]] std::string caveat() const override;
  [[nodiscard]] bool network() const override { return false; }

 private:
  boost::asio::io_context& io_;
  BusConfig bus_;
  boost::asio::serial_port port_;
  PortLock lock_;        // held while the port is open
  std::string refused_;  // the settings the port did not take at its last open
  std::array<std::uint8_t, 512> chunk_{};
  Bytes tx_;
};

}  // namespace drivegate
