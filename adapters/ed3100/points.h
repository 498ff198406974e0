// The adapter's own points: the fault/state pair of 0x0E01 and its bits, the frequency reference,
// then three points per monitor and one per parameter, as the options list them.
#pragma once

#include <cstddef>
#include <vector>

#include "drivegate/point.h"
#include "settings.h"

namespace drivegate::ed3100 {

// Index of each fixed point in points() / values(); the monitors' and parameters' follow.
namespace pt {
inline constexpr std::size_t drive_fault_code = 0;     // 0x0E01 word 1, raw
inline constexpr std::size_t state_word = 1;           // 0x0E01 word 2, raw
inline constexpr std::size_t running = 2;              // state bit 4
inline constexpr std::size_t direction = 3;            // state bit 1
inline constexpr std::size_t commanded_direction = 4;  // state bit 3
inline constexpr std::size_t accelerating = 5;         // state bit 10
inline constexpr std::size_t decelerating = 6;         // state bit 11
inline constexpr std::size_t frequency_setpoint = 7;   // holding: the reference for 0x2001
inline constexpr std::size_t count = 8;                // fixed points

// Per monitor m: its scaled value, its raw value, its format word.
inline constexpr std::size_t kPerMonitor = 3;
constexpr std::size_t monitor_value(std::size_t m) {
  return count + kPerMonitor * m;
}
constexpr std::size_t monitor_raw(std::size_t m) {
  return monitor_value(m) + 1;
}
constexpr std::size_t monitor_format(std::size_t m) {
  return monitor_value(m) + 2;
}
// Parameter p, after every monitor.
inline std::size_t parameter(const Settings& s, std::size_t p) {
  return count + kPerMonitor * s.monitors.size() + p;
}
}  // namespace pt

std::vector<PointSpec> make_points(const Settings& s);

}  // namespace drivegate::ed3100
