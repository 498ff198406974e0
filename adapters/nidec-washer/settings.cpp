#include "settings.h"

namespace drivegate::nidec {

std::optional<Settings> parse_settings(const Options& options, std::string& error) {
  // Values the schema let through that a frame cannot carry: none today, as every range of
  // kOptionSchema is the field's own. Checked all the same, so a widened schema fails loudly.
  const std::int64_t platform = options.integer("platform");
  const std::int64_t empty = options.integer("empty_raw_weight");
  const std::int64_t accel_ms = options.integer("accel_time_ms");
  const std::int64_t attempts = options.integer("attempts");
  if (platform < 0 || platform > 0xFF) {
    error = "platform: one byte (5.1), 0..255";
    return std::nullopt;
  }
  if (empty < 0 || empty > 0xFFFF) {
    error = "empty_raw_weight: two bytes (5.1), 0..65535";
    return std::nullopt;
  }
  // 5.3: 100 ms units, rounded to the nearest.
  const std::int64_t accel_100ms = (accel_ms + 50) / 100;
  if (accel_ms < 0 || accel_100ms > 0xFFFF) {
    error = "accel_time_ms: two bytes of 100 ms (5.3), 0..6553500";
    return std::nullopt;
  }
  if (attempts < 1 || attempts > 0xFF) {
    error = "attempts: 1..255";
    return std::nullopt;
  }
  Settings s;
  s.platform = static_cast<std::uint8_t>(platform);
  s.empty_raw_weight = static_cast<std::uint16_t>(empty);
  s.accel_100ms = static_cast<std::uint16_t>(accel_100ms);
  s.attempts = static_cast<std::uint8_t>(attempts);
  return s;
}

}  // namespace drivegate::nidec
