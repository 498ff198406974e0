// Opens and configures one serial port for the bus engine: baud, parity, data and stop bits,
// raw mode, and optionally the kernel's RS-485 mode (the UART drives the transceiver's DE line).
// The port is taken exclusively first (transport/port_lock.h): `lock` holds it until released.
#pragma once

#include <boost/asio/serial_port.hpp>
#include <system_error>

#include "config/config.h"
#include "transport/port_lock.h"

namespace drivegate {

// PortError::in_use (lock.owner() says who) when another program has the port.
std::error_code open_serial(boost::asio::serial_port& port, const BusConfig& bus, PortLock& lock);

}  // namespace drivegate
