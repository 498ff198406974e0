#include "settings.h"

namespace drivegate::fdc1 {

std::optional<Settings> parse_settings(const Options& options, std::string& /*error*/) {
  Settings s;
  s.slave_mode = options.boolean("slave_mode");
  s.refresh = std::chrono::seconds(options.integer("refresh_s"));
  s.confirm = std::chrono::milliseconds(options.integer("confirm_ms"));
  s.stale = std::chrono::milliseconds(options.integer("stale_ms"));
  s.tolerance_rpm = static_cast<int>(options.integer("tolerance_rpm"));
  s.allow_nv_programming = options.boolean("allow_nv_programming");
  return s;
}

}  // namespace drivegate::fdc1
