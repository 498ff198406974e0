#include "settings.h"

namespace drivegate::unicla {

std::optional<Settings> parse_settings(const Options& options, std::string& error) {
  Settings s;
  const std::string& order = options.string("byte_order");
  if (order == "big") {
    s.byte_order = ByteOrder::big;
  } else if (order == "little") {
    s.byte_order = ByteOrder::little;
  } else {
    error = "byte_order: big or little, not '" + order + "'";
    return std::nullopt;
  }
  s.reply_timeout = std::chrono::milliseconds(options.integer("reply_timeout_ms"));
  s.attempts = static_cast<std::uint8_t>(1 + options.integer("retries"));
  s.confirm_timeout = std::chrono::milliseconds(options.integer("confirm_timeout_ms"));
  return s;
}

}  // namespace drivegate::unicla
