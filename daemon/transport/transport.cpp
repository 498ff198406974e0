#include "transport/transport.h"

#include <boost/asio/error.hpp>

#include "config/port_address.h"
#include "transport/rfc2217_transport.h"
#include "transport/serial_transport.h"
#include "transport/tcp_transport.h"

namespace drivegate {

std::error_code from_asio(const boost::system::error_code& ec) {
  if (!ec) return {};
  if (ec.category() == boost::system::system_category() ||
      ec.category() == boost::system::generic_category()) {
    return {ec.value(), std::generic_category()};
  }
  return ec;
}

bool closed_by_peer(const std::error_code& ec) {
  return ec == from_asio(boost::asio::error::eof);
}

std::unique_ptr<Transport> make_transport(boost::asio::io_context& io, const BusConfig& bus,
                                          std::shared_ptr<spdlog::logger> log) {
  std::string error;
  const auto address = parse_port_address(bus.port, error);
  if (address && address->kind == PortAddress::Kind::tcp) {
    return std::make_unique<TcpTransport>(io, address->host, address->port);
  }
  if (address && address->kind == PortAddress::Kind::rfc2217) {
    return std::make_unique<Rfc2217Transport>(io, bus, address->host, address->port,
                                              std::move(log));
  }
  // A tty, or a port the configuration did not check (tests): opening it says what is wrong.
  return std::make_unique<SerialTransport>(io, bus);
}

}  // namespace drivegate
