#include "serial_line.h"

#include <linux/serial.h>
#include <sys/ioctl.h>
#include <termios.h>

#include <cerrno>

#include "transport/transport.h"

namespace drivegate {

namespace asio = boost::asio;

namespace {

std::error_code last_errno() {
  return {errno, std::generic_category()};
}

// Baud, character size, parity, stop bits, no flow control; stops at the first that fails.
std::error_code set_framing(asio::serial_port& port, const BusConfig& bus) {
  using sp = asio::serial_port_base;
  const auto parity = bus.parity == Parity::none   ? sp::parity::none
                      : bus.parity == Parity::even ? sp::parity::even
                                                   : sp::parity::odd;
  const auto stop = bus.stop_bits == 2 ? sp::stop_bits::two : sp::stop_bits::one;
  boost::system::error_code ec;
  port.set_option(sp::baud_rate(bus.baud), ec);
  if (!ec) port.set_option(sp::character_size(bus.data_bits), ec);
  if (!ec) port.set_option(sp::parity(parity), ec);
  if (!ec) port.set_option(sp::stop_bits(stop), ec);
  if (!ec) port.set_option(sp::flow_control(sp::flow_control::none), ec);
  return from_asio(ec);
}

// Everything after open(): the port is open, and the caller closes it if this fails.
std::error_code configure(asio::serial_port& port, const BusConfig& bus) {
  if (const std::error_code ec = set_framing(port, bus)) return ec;
  const int fd = port.native_handle();
  // Drop whatever the line held before we owned it.
  if (::tcflush(fd, TCIOFLUSH) != 0) return last_errno();
  if (bus.rs485) {
    // The UART drives the transceiver's DE line with RTS while it sends.
    serial_rs485 rs485{};
    rs485.flags = SER_RS485_ENABLED | SER_RS485_RTS_ON_SEND;
    if (::ioctl(fd, TIOCSRS485, &rs485) != 0) return last_errno();
  }
  return {};
}

std::string_view parity_name(asio::serial_port_base::parity::type p) {
  using sp = asio::serial_port_base;
  return p == sp::parity::none ? "none" : p == sp::parity::even ? "even" : "odd";
}

}  // namespace

std::string refused_settings(asio::serial_port& port, const BusConfig& bus) {
  using sp = asio::serial_port_base;
  std::string out;
  const auto refused = [&](const std::string& asked, const std::string& held) {
    out += (out.empty() ? "" : ", ") + asked + " (the port has " + held + ")";
  };
  // Each read back from the port's termios (tcgetattr) as Asio set it.
  boost::system::error_code ec;
  sp::baud_rate baud;
  port.get_option(baud, ec);
  if (!ec && baud.value() != bus.baud) {
    refused("baud " + std::to_string(bus.baud), std::to_string(baud.value()));
  }
  sp::character_size size;
  port.get_option(size, ec);
  if (!ec && size.value() != bus.data_bits) {
    refused("data bits " + std::to_string(bus.data_bits), std::to_string(size.value()));
  }
  sp::parity parity;
  port.get_option(parity, ec);
  const std::string_view asked = to_string(bus.parity);
  if (!ec && parity_name(parity.value()) != asked) {
    refused("parity " + std::string(asked), std::string(parity_name(parity.value())));
  }
  sp::stop_bits stop;
  port.get_option(stop, ec);
  const unsigned held_stop = stop.value() == sp::stop_bits::two ? 2 : 1;
  if (!ec && held_stop != bus.stop_bits) {
    refused("stop bits " + std::to_string(bus.stop_bits), std::to_string(held_stop));
  }
  return out;
}

std::error_code open_serial(asio::serial_port& port, const BusConfig& bus, PortLock& lock,
                            std::string* refused) {
  if (const std::error_code ec = lock.acquire(bus.port)) return ec;
  boost::system::error_code opened;
  port.open(bus.port, opened);
  if (opened) {
    lock.release();
    // Another program's TIOCEXCL (one that keeps no lock file).
    if (opened == boost::system::errc::device_or_resource_busy) return PortError::in_use;
    return from_asio(opened);
  }
  std::error_code ec = make_exclusive(port.native_handle());
  if (!ec) ec = configure(port, bus);
  if (!ec && refused != nullptr) *refused = refused_settings(port, bus);
  if (ec) {
    // The error_code overload: this path reports, it never throws. The step's error is the one
    // worth reporting, not close()'s.
    boost::system::error_code ignored;
    port.close(ignored);
    lock.release();
  }
  return ec;
}

}  // namespace drivegate
