// Opens and configures one serial port for the bus engine: baud, parity, data and stop bits,
// raw mode, and optionally the kernel's RS-485 mode (the UART drives the transceiver's DE line).
#pragma once

#include <boost/asio/serial_port.hpp>
#include <system_error>

#include "config/config.h"

namespace drivegate {

std::error_code open_serial(boost::asio::serial_port& port, const BusConfig& bus);

}  // namespace drivegate
