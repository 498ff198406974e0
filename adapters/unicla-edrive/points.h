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
inline constexpr std::size_t suction_pressure = 0;
inline constexpr std::size_t discharge_pressure = 1;
inline constexpr std::size_t suction_temperature = 2;
inline constexpr std::size_t discharge_temperature = 3;
inline constexpr std::size_t suction_superheat = 4;
inline constexpr std::size_t discharge_superheat = 5;
inline constexpr std::size_t compressor_rpm = 6;
inline constexpr std::size_t motor_voltage = 7;
inline constexpr std::size_t motor_power = 8;
inline constexpr std::size_t motor_torque = 9;
inline constexpr std::size_t op_state = 10;
inline constexpr std::size_t control_mode = 11;
inline constexpr std::size_t demand = 12;
inline constexpr std::size_t remote_enable = 13;
inline constexpr std::size_t anti_short = 14;
inline constexpr std::size_t motor_temperature = 15;
inline constexpr std::size_t switch_temperature = 16;
inline constexpr std::size_t compressor_safety_run = 17;
inline constexpr std::size_t compressor_safety_start = 18;
inline constexpr std::size_t motor_safety_run = 19;
inline constexpr std::size_t motor_safety_start = 20;
inline constexpr std::size_t electrical_safety = 21;
// Build Information (0x02)
inline constexpr std::size_t model = 22;
inline constexpr std::size_t serial_number = 23;
inline constexpr std::size_t refrigerant = 24;
inline constexpr std::size_t oil = 25;
inline constexpr std::size_t build_min_speed = 26;
inline constexpr std::size_t build_max_speed = 27;
inline constexpr std::size_t rated_voltage = 28;
inline constexpr std::size_t rated_power = 29;
inline constexpr std::size_t device_name = 30;
// Running Limits / RS485 Config (0x03)
inline constexpr std::size_t limit_min_speed = 31;
inline constexpr std::size_t limit_max_speed = 32;
inline constexpr std::size_t suction_pressure_low = 33;
inline constexpr std::size_t suction_pressure_high = 34;
inline constexpr std::size_t discharge_pressure_low = 35;
inline constexpr std::size_t discharge_pressure_high = 36;
inline constexpr std::size_t suction_temperature_low = 37;
inline constexpr std::size_t suction_temperature_high = 38;
inline constexpr std::size_t discharge_temperature_low = 39;
inline constexpr std::size_t discharge_temperature_high = 40;
inline constexpr std::size_t suction_superheat_low = 41;
inline constexpr std::size_t suction_superheat_high = 42;
inline constexpr std::size_t discharge_superheat_low = 43;
inline constexpr std::size_t discharge_superheat_high = 44;
inline constexpr std::size_t rs485_device_id = 45;
inline constexpr std::size_t control_enabled = 46;
inline constexpr std::size_t count = 47;
}  // namespace pt

std::vector<PointSpec> make_points();
// The payloads' fields into values() (sized pt::count).
void fill_status(std::vector<Value>& v, const Status& s);
void fill_build_info(std::vector<Value>& v, const BuildInfo& b);
void fill_running_limits(std::vector<Value>& v, const RunningLimits& l);

}  // namespace drivegate::unicla
