// The Modbus serial line codec (RTU and ASCII) is shared with the daemon's serial listeners, so
// it lives below both, in codecs/modbus_serial/serial_codec.h (library dg_modbus_serial), which
// includes no daemon header; the adapter uses its names as its own.
#pragma once

#include "modbus_serial/serial_codec.h"

namespace drivegate::modbus_device {
using namespace drivegate::modbus_serial;  // NOLINT(google-build-using-namespace): one codec
}  // namespace drivegate::modbus_device
