// Opens and configures one serial port for the bus engine: baud, parity, data and stop bits,
// raw mode, and optionally the kernel's RS-485 mode (the UART drives the transceiver's DE line).
// The port is taken exclusively first (transport/port_lock.h): `lock` holds it until released.
#pragma once

#include <boost/asio/serial_port.hpp>
#include <string>
#include <system_error>

#include "config/config.h"
#include "transport/port_lock.h"

namespace drivegate {

// PortError::in_use (lock.owner() says who) when another program has the port. Once it is open,
// its settings are read back: a port that silently kept others than asked (a pseudo-terminal
// has no parity and always 8 data bits; some USB adapters ignore a parity or a stop bit) is
// still open, and `refused` (when given) names each setting it did not take, else is emptied.
std::error_code open_serial(boost::asio::serial_port& port, const BusConfig& bus, PortLock& lock,
                            std::string* refused = nullptr);

// What the open `port` holds of `bus`'s baud, data bits, parity and stop bits, as "parity even
// (the port has none), data bits 7 (it has 8)"; empty when it holds all of them.
std::string refused_settings(boost::asio::serial_port& port, const BusConfig& bus);

}  // namespace drivegate
