// The adapter's own points: every field of the Status, Build Information and Running Limits
// payloads, with units and the document's enum and flag labels. All read-only: the drive's only
// writes are Set Run State and Acknowledge Faults, which the common block's command and
// setpoint_rpm carry.
#pragma once

#include <cstddef>
#include <vector>

#include "drivegate/point.h"
#include "payloads.h"

namespace drivegate::unicla {

// Index of each point in points() / values().
namespace pt {
// Status (0x01)
enum : std::size_t {
  suction_pressure,
  discharge_pressure,
  suction_temperature,
  discharge_temperature,
  suction_superheat,
  discharge_superheat,
  compressor_rpm,
  motor_voltage,
  motor_power,
  motor_torque,
  op_state,
  control_mode,
  demand,
  remote_enable,
  anti_short,
  motor_temperature,
  switch_temperature,
  compressor_safety_run,
  compressor_safety_start,
  motor_safety_run,
  motor_safety_start,
  electrical_safety,
  // Build Information (0x02)
  model,
  serial_number,
  refrigerant,
  oil,
  build_min_speed,
  build_max_speed,
  rated_voltage,
  rated_power,
  device_name,
  // Running Limits / RS485 Config (0x03)
  limit_min_speed,
  limit_max_speed,
  suction_pressure_low,
  suction_pressure_high,
  discharge_pressure_low,
  discharge_pressure_high,
  suction_temperature_low,
  suction_temperature_high,
  discharge_temperature_low,
  discharge_temperature_high,
  suction_superheat_low,
  suction_superheat_high,
  discharge_superheat_low,
  discharge_superheat_high,
  rs485_device_id,
  control_enabled,
  count,
};
}  // namespace pt

std::vector<PointSpec> make_points();
// The payloads' fields into values() (sized pt::count).
void fill_status(std::vector<Value>& v, const Status& s);
void fill_build_info(std::vector<Value>& v, const BuildInfo& b);
void fill_running_limits(std::vector<Value>& v, const RunningLimits& l);

}  // namespace drivegate::unicla
