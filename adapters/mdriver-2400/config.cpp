#include "config.h"

#include "codec.h"

namespace drivegate::mdriver {

std::optional<Config> make_config(std::uint32_t address, const Options& options,
                                  std::string& error) {
  Config c;
  const std::int64_t master = options.integer(kOptMasterAddress);
  if (address > 0xFF || master < 0 || master > 0xFF) {
    error = "master_address and the device address are one byte each (0..255)";
    return std::nullopt;
  }
  if (static_cast<std::uint32_t>(master) == address) {
    error = "master_address must differ from the device address";
    return std::nullopt;
  }
  c.master = static_cast<std::uint8_t>(master);
  c.device = static_cast<std::uint8_t>(address);
  const std::string& mode = options.string(kOptMode);
  if (mode == "normal") {
    c.change = kChangeNormal;
  } else if (mode == "continuous") {
    c.change = kChangeContinuous;
  } else {
    error = "mode must be normal or continuous";
    return std::nullopt;
  }
  c.keepalive = Millis(options.integer(kOptKeepalive));
  return c;
}

}  // namespace drivegate::mdriver
