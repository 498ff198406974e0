#include "settings.h"

#include <string_view>

namespace drivegate::nidec {
namespace {

// Whether the schema's range of option `name` lies within [lo, hi].
constexpr bool schema_within(std::string_view name, double lo, double hi) {
  for (const OptionSpec& o : kOptionSchema) {
    if (o.name == name) return o.min >= lo && o.max <= hi;
  }
  return false;
}

// Every range of kOptionSchema is the field's own, so every value the gateway lets through fits
// its frame: a schema widened past its field does not compile.
static_assert(schema_within("platform", 0, 0xFF));            // 5.1: ping byte 3
static_assert(schema_within("empty_raw_weight", 0, 0xFFFF));  // 5.1: ping bytes 4-5
// 5.3: two bytes of 100 ms, rounded to the nearest.
static_assert(schema_within("accel_time_ms", 0, 0xFFFF * 100 + 49));
static_assert(schema_within("attempts", 1, 0xFF));  // a byte counts them

}  // namespace

std::optional<Settings> parse_settings(const Options& options, std::string& /*error*/) {
  Settings s;
  s.platform = static_cast<std::uint8_t>(options.integer("platform"));
  s.empty_raw_weight = static_cast<std::uint16_t>(options.integer("empty_raw_weight"));
  // 5.3: 100 ms units, rounded to the nearest.
  s.accel_100ms = static_cast<std::uint16_t>((options.integer("accel_time_ms") + 50) / 100);
  s.attempts = static_cast<std::uint8_t>(options.integer("attempts"));
  return s;
}

}  // namespace drivegate::nidec
