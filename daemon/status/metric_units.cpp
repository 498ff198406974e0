#include "status/metric_units.h"

#include <algorithm>
#include <cmath>

namespace drivegate {

std::optional<MetricUnit> metric_unit(std::string_view unit) {
  if (unit.empty()) return std::nullopt;
  const auto* it = std::find_if(kKnownUnits.begin(), kKnownUnits.end(),
                                [&](const KnownUnit& k) { return k.unit == unit; });
  if (it == kKnownUnits.end()) return std::nullopt;
  return it->metric;
}

double round_significant(double value, int digits) {
  if (value == 0 || !std::isfinite(value)) return value;
  // 10^(digits - 1 - exponent) brings the last digit kept just left of the point; past 10^15
  // the value has no more digits than that already (and the power would overflow first).
  const int exponent = static_cast<int>(std::floor(std::log10(std::fabs(value))));
  const int shift = digits - 1 - exponent;
  if (shift <= 0 || shift > 300) return value;
  const double factor = std::pow(10.0, shift);
  const double scaled = value * factor;
  if (std::fabs(scaled) >= 9007199254740992.0) return value;  // 2^53: no fraction left to cut
  return std::round(scaled) / factor;
}

}  // namespace drivegate
