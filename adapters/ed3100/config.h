// The ed3100 device options, parsed once from the validated Options (schema in plugin.cpp).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivegate/driver.h"
#include "drivegate/options.h"

namespace drivegate::ed3100 {

struct MonitorSel {
  std::uint16_t reg = 0;  // 0x0D00..0x0D28
  std::string unit;       // "V", "Hz", "A" or "" (from a ":unit" suffix)
};

struct Config {
  std::uint8_t address = 1;
  int poles = 4;
  std::vector<MonitorSel> monitors;       // polled and exposed, speed monitor included
  std::size_t speed_monitor = 0;          // index into monitors
  std::vector<std::uint16_t> parameters;  // 0xGGnn
  Millis frame_gap{10};
  Millis timeout{100};
  std::uint8_t attempts = 3;
  Millis comm_timeout{3000};
  std::uint16_t reset_register = 0x2002;
  std::uint16_t reset_value = 0x0002;
};

// "0D00", "0d05:Hz": a monitor register and its unit.
std::optional<MonitorSel> parse_monitor(std::string_view text);
// "04-01" -> 0x0401 (the digits are the address's hex digits, document "GGnnH").
std::optional<std::uint16_t> parse_parameter(std::string_view text);

// Returns nullopt and sets `error` (one line, naming the option) when the options do not make
// a device.
std::optional<Config> make_config(std::uint32_t address, const Options& options,
                                  std::string& error);

}  // namespace drivegate::ed3100
