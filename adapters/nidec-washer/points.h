// The adapter's own points (after the common block), their indices, and the enums their values
// name.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "drivegate/point.h"

namespace drivegate::nidec {

// What run_forward / run_reverse start (holding point `motion`).
enum class Motion : std::uint16_t {
  rotation = 0,         // forward = CW 0x09 (5.3), reverse = CCW 0x0B (5.4)
  spin = 1,             // 0x0D (5.6), forward only
  agitation = 2,        // 0x0C (5.5), forward only
  free_shaft_spin = 3,  // 0x1D (5.14), forward only
};
inline constexpr std::array<std::string_view, 4> kMotionNames = {"rotation", "spin", "agitation",
                                                                 "free_shaft_spin"};

// One-shot requests (holding point `action`).
enum class Action : std::uint16_t {
  none = 0,
  voltage_detection = 1,     // 0x2B (5.9)
  weight_detection = 2,      // 0x2C (5.10)
  fabric_detection = 3,      // 0x2D (5.11)
  forced_brake_enable = 4,   // 0x1B 01 (5.13)
  forced_brake_disable = 5,  // 0x1B 00 (5.13)
  fct_test = 6,              // 0x66 (5.15)
  ping = 7,                  // 0x02 (5.1), sent again on request
};
inline constexpr std::array<std::string_view, 8> kActionNames = {"none",
                                                                 "voltage_detection",
                                                                 "weight_detection",
                                                                 "fabric_detection",
                                                                 "forced_brake_enable",
                                                                 "forced_brake_disable",
                                                                 "fct_test",
                                                                 "ping"};

// Outcome of the last `action` (input point `action_status`).
enum class ActionStatus : std::uint16_t { idle = 0, pending = 1, done = 2, no_response = 3 };
inline constexpr std::array<std::string_view, 4> kActionStatusNames = {"idle", "pending", "done",
                                                                       "no_response"};

// Indices into points() / values().
namespace pt {
enum : std::size_t {
  motion,
  accel_time,
  agitation_accel,
  agitation_decel,
  agitation_cw_on,
  agitation_cw_off,
  agitation_ccw_on,
  agitation_ccw_off,
  action,
  action_status,
  inverter_version,
  platform,
  error_bits,
  weight,
  raw_weight,
  dc_bus_voltage,
  forced_brake,
  fabric_raw,
  fct_error,
  fct_speed_rpm,
  fct_ipm_temperature,
  fct_ipm_model_bus_volt_high,
  fct_bus_volt_low,
  fct_phase_current,
  count,
};
}  // namespace pt

// The seconds a time point shows for a field of 100 ms units (5.3 accel, 5.5 agitation).
constexpr double seconds_of(std::int64_t units_100ms) {
  return static_cast<double>(units_100ms) / 10.0;
}

// Whether a point is one of the agitation times (5.5), laid out in frame order.
constexpr bool is_agitation_time(std::size_t point) {
  return point >= pt::agitation_accel && point <= pt::agitation_ccw_off;
}

std::vector<PointSpec> make_points();

}  // namespace drivegate::nidec
