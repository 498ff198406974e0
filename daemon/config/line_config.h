// A serial line's settings as drivegate.toml gives them: a [[bus]]'s (the drives' line) and a
// serial [[listener]]'s (a master's line) are read by the same code, so the two accept the same
// keys with the same checks and messages.
#pragma once

#include <string>

#include "config.h"
#include "drivegate/toml_reader.h"

namespace drivegate {

// Which line settings the table set itself (a bus takes the rest from its devices' adapter).
struct LineGiven {
  bool baud = false;
  bool parity = false;
  bool data_bits = false;
  bool stop_bits = false;
  bool echo = false;
  [[nodiscard]] bool framing() const { return baud && parity && data_bits && stop_bits; }
};

// port (a device, tcp:// or rfc2217://, required), baud (a standard rate), parity, data_bits,
// stop_bits, echo, rs485 (a local port only), network_delay_ms and reopen_max_ms into `line`.
LineGiven read_line(TableReader& r, const std::string& prefix, BusConfig& line, Diagnostics& diag);

}  // namespace drivegate
