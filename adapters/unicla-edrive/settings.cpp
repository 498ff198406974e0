#include "settings.h"

namespace drivegate::unicla {

std::optional<Settings> parse_settings(const Options& o, std::string& error) {
  Settings s;
  if (o.has("byte_order")) {
    const std::string& order = o.string("byte_order");
    if (order == "little") {
      s.byte_order = ByteOrder::little;
    } else if (order != "big") {
      error = "byte_order: expected big or little, got '" + order + "'";
      return std::nullopt;
    }
  }
  if (o.has("reply_timeout_ms"))
    s.reply_timeout = std::chrono::milliseconds(o.integer("reply_timeout_ms"));
  if (o.has("retries")) s.attempts = static_cast<std::uint8_t>(1 + o.integer("retries"));
  if (o.has("confirm_timeout_ms")) {
    s.confirm_timeout = std::chrono::milliseconds(o.integer("confirm_timeout_ms"));
  }
  if (s.reply_timeout.count() <= 0 || s.confirm_timeout.count() <= 0) {
    error = "reply_timeout_ms and confirm_timeout_ms must be positive";
    return std::nullopt;
  }
  return s;
}

}  // namespace drivegate::unicla
