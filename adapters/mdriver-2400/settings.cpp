#include "settings.h"

#include "codec.h"

namespace drivegate::mdriver {

std::optional<Settings> parse_settings(const Options& options, std::string& error) {
  Settings s;
  const std::int64_t master = options.integer("master_address");
  if (master < 0 || master > 0xFF) {  // Section 2: one-byte addresses
    error = "master_address: one byte (0..255)";
    return std::nullopt;
  }
  s.master = static_cast<std::uint8_t>(master);
  const std::string& mode = options.string("mode");
  if (mode == "normal") {
    s.change = kChangeNormal;
  } else if (mode == "continuous") {
    s.change = kChangeContinuous;
  } else {
    error = "mode: normal or continuous, not '" + mode + "'";
    return std::nullopt;
  }
  s.keepalive = std::chrono::milliseconds(options.integer("keepalive_ms"));
  return s;
}

std::optional<std::uint8_t> device_address(std::uint32_t address, const Settings& settings,
                                           std::string& error) {
  if (address > 0xFF) {  // Section 2: one-byte addresses
    error = "address: one byte (0..255)";
    return std::nullopt;
  }
  // Section 2: the driver answers frames whose destination is its own address, to the master's:
  // with both the same, its replies would look like requests.
  if (address == settings.master) {
    error = "master_address: must differ from the device address";
    return std::nullopt;
  }
  return static_cast<std::uint8_t>(address);
}

}  // namespace drivegate::mdriver
