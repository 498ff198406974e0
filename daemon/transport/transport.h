// What a Bus moves its bytes through: a local serial port, a raw TCP connection to a serial
// device server, or RFC 2217 (Telnet COM-PORT-OPTION) over TCP. The bus engine, its timeouts,
// retries, echo check and counters are the same on each; only this differs. A transport owns
// its file descriptor; every completion comes from the io_context, never from inside a call.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/io_context.hpp>
#include <boost/system/error_code.hpp>
#include <functional>
#include <memory>
#include <string>
#include <system_error>

#include "config/config.h"
#include "drivegate/bytes.h"

namespace drivegate {

class Transport {
 public:
  using Done = std::function<void(std::error_code)>;
  // Line data (the transport's own framing removed), valid only during the call.
  using Received = std::function<void(std::error_code, ByteView)>;

  virtual ~Transport() = default;
  // Opens (a network transport connects and, for RFC 2217, sets the line settings).
  virtual void open(Done done) = 0;
  // The next line data. One read outstanding at a time.
  virtual void read(Received received) = 0;
  // Writes line data (escaped as the transport needs); `done` once the kernel has all of it.
  virtual void write(ByteView data, Done done) = 0;
  // Closes; operations outstanding complete with operation_aborted.
  virtual void close() = 0;
  // For the log: "/dev/ttyUSB0 (9600 baud, 8 data, parity even, 1 stop)", "tcp 10.1.5.20:4001".
  [[nodiscard]] virtual std::string describe() const = 0;
  // Why `ec` happened, for the log: its message, or more where the transport knows more (the
  // program that holds a serial port).
  [[nodiscard]] virtual std::string explain(std::error_code ec) const { return ec.message(); }
  // What an open that succeeded should warn of (a stale port lock it could not remove), or empty.
  [[nodiscard]] virtual std::string caveat() const { return {}; }
  // A network transport's peer may hang while its TCP connection stays up: the bus reconnects
  // when every device on it went silent (Bus::check_silence).
  [[nodiscard]] virtual bool network() const = 0;
};

// Asio's error into the std::error_code a transport reports: errno values (Boost's system and
// generic categories) become std's generic category, so they compare equal to std::errc
// (operation_canceled after close(), connection_refused...); Asio's own categories (end of file,
// already open) are wrapped by Boost's std interoperability, keeping value, name and message.
std::error_code from_asio(const boost::system::error_code& ec);
// The peer closed the connection (end of file on a socket).
bool closed_by_peer(const std::error_code& ec);

// The transport `bus.port` names (config/port_address.h); the configuration checked it.
std::unique_ptr<Transport> make_transport(boost::asio::io_context& io, const BusConfig& bus,
                                          std::shared_ptr<spdlog::logger> log);

}  // namespace drivegate
