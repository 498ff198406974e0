// The ed3100 point table: fixed state points, then three per monitor, then one per parameter.
#pragma once

#include <cstddef>
#include <vector>

#include "config.h"
#include "drivegate/point.h"

namespace drivegate::ed3100 {

// Fixed points, in this order at the start of the table.
enum class Fixed : std::size_t {
  fault_code,           // 0x0E01 word 1, raw
  state_word,           // 0x0E01 word 2, raw
  running,              // state bit 4
  direction,            // state bit 1
  commanded_direction,  // state bit 3
  accelerating,         // state bit 10
  decelerating,         // state bit 11
  frequency_setpoint,   // holding: the frequency reference for 0x2001, 0.01 Hz
  count,
};

inline constexpr std::size_t index(Fixed f) {
  return static_cast<std::size_t>(f);
}
inline constexpr std::size_t kFixedCount = index(Fixed::count);
// Per monitor: scaled value, raw value, format word.
inline constexpr std::size_t kPointsPerMonitor = 3;

inline constexpr std::size_t monitor_value_index(std::size_t m) {
  return kFixedCount + kPointsPerMonitor * m;
}
inline std::size_t parameter_index(const Config& c, std::size_t p) {
  return kFixedCount + kPointsPerMonitor * c.monitors.size() + p;
}

std::vector<PointSpec> make_points(const Config& c);

}  // namespace drivegate::ed3100
