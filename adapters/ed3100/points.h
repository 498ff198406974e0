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
enum : std::size_t {
  drive_fault_code,     // 0x0E01 word 1, raw
  state_word,           // 0x0E01 word 2, raw
  running,              // state bit 4
  direction,            // state bit 1
  commanded_direction,  // state bit 3
  accelerating,         // state bit 10
  decelerating,         // state bit 11
  frequency_setpoint,   // holding: the reference for 0x2001
  count,                // fixed points
};

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
