#include "serial_line.h"

#include <linux/serial.h>
#include <sys/ioctl.h>
#include <termios.h>

namespace drivegate {

namespace asio = boost::asio;

std::error_code open_serial(asio::serial_port& port, const BusConfig& bus) {
  boost::system::error_code ec;
  port.open(bus.port, ec);
  if (ec) return std::error_code(ec.value(), std::generic_category());
  using sp = asio::serial_port_base;
  const auto parity = bus.parity == Parity::none   ? sp::parity::none
                      : bus.parity == Parity::even ? sp::parity::even
                                                   : sp::parity::odd;
  const auto stop = bus.stop_bits == 2 ? sp::stop_bits::two : sp::stop_bits::one;
  port.set_option(sp::baud_rate(bus.baud), ec);
  if (!ec) port.set_option(sp::character_size(bus.data_bits), ec);
  if (!ec) port.set_option(sp::parity(parity), ec);
  if (!ec) port.set_option(sp::stop_bits(stop), ec);
  if (!ec) port.set_option(sp::flow_control(sp::flow_control::none), ec);
  if (ec) {
    port.close();
    return std::error_code(ec.value(), std::generic_category());
  }
  const int fd = port.native_handle();
  // Drop whatever the line held before we owned it.
  ::tcflush(fd, TCIOFLUSH);
  if (bus.rs485) {
    serial_rs485 rs485{};
    rs485.flags = SER_RS485_ENABLED | SER_RS485_RTS_ON_SEND;
    if (::ioctl(fd, TIOCSRS485, &rs485) != 0) {
      const int err = errno;
      port.close();
      return std::error_code(err, std::generic_category());
    }
  }
  return {};
}

std::chrono::microseconds char_time(const BusConfig& bus) {
  const unsigned bits = 1u + bus.data_bits + (bus.parity == Parity::none ? 0u : 1u) + bus.stop_bits;
  return std::chrono::microseconds(bits * 1'000'000ull / std::max<std::uint32_t>(bus.baud, 1));
}

}  // namespace drivegate
