// Pure layouts of the three read payloads and the Set Run State payload (eDrive RS485 Interface
// V16, "Status", "Build Information", "Running Limits/ RS485 Config", "Commands"). Each payload
// is a stack of 8-byte rows; the positions inside a row are drivegate's reading of the tables
// (see README.md, "Payload layouts").
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "drivegate/bytes.h"

namespace drivegate::unicla {

// The document states the order of integers only by example (speed 1000 = 03 E8, big-endian);
// the order of floats is not stated. Integers are always big-endian; floats follow this.
enum class ByteOrder : std::uint8_t { big, little };

// "Message IDs" / "Examples": payload sizes.
inline constexpr std::size_t kStatusSize = 64;         // 8 rows ("Status": 0x40 in the example)
inline constexpr std::size_t kBuildInfoSize = 80;      // 10 rows
inline constexpr std::size_t kRunningLimitsSize = 64;  // 8 rows
inline constexpr std::size_t kSetRunStateSize = 2;     // "Set Run State: 2, unsigned 16bit"

struct Range {
  float low = 0;
  float high = 0;
  friend bool operator==(const Range&, const Range&) = default;
};

struct Status {
  float suction_pressure = 0;  // bar-a
  float discharge_pressure = 0;
  float suction_temperature = 0;  // degC
  float discharge_temperature = 0;
  float suction_superheat = 0;  // K
  float discharge_superheat = 0;
  std::uint16_t rpm = 0;
  std::uint16_t volts = 0;
  std::uint16_t watts = 0;
  std::uint16_t torque = 0;   // Nm
  std::uint8_t op_state = 0;  // ED_OP_STATE (op_state.h), raw: a state past the list is kept
  std::uint8_t control_mode = 0;
  std::uint8_t demand = 0;  // %
  std::uint8_t remote_enable = 0;
  std::uint8_t anti_short = 0;
  float motor_temperature = 0;  // degC
  float switch_temperature = 0;
  std::uint16_t compressor_run_flags = 0;
  std::uint16_t compressor_start_flags = 0;
  std::uint16_t motor_run_flags = 0;
  std::uint16_t motor_start_flags = 0;
  std::uint32_t electrical_flags = 0;  // 24 bits
  friend bool operator==(const Status&, const Status&) = default;
};

struct BuildInfo {
  std::string model;             // 16 ASCII
  std::string serial;            // 16 ASCII
  std::uint8_t refrigerant = 0;  // ED_REFRIGERANTS
  std::uint8_t oil = 0;          // ED_OILS
  std::uint16_t min_speed = 0;   // rpm
  std::uint16_t max_speed = 0;
  std::uint16_t voltage = 0;  // V
  std::uint16_t power = 0;    // W
  std::string device_name;    // 32 ASCII
  friend bool operator==(const BuildInfo&, const BuildInfo&) = default;
};

struct RunningLimits {
  std::uint16_t min_speed = 0;  // rpm
  std::uint16_t max_speed = 0;
  Range suction_pressure;  // bar-a
  Range discharge_pressure;
  Range suction_temperature;  // degC
  Range discharge_temperature;
  Range suction_superheat;  // K
  Range discharge_superheat;
  std::uint8_t device_id = 0;
  std::uint8_t control_enabled = 0;
  friend bool operator==(const RunningLimits&, const RunningLimits&) = default;
};

inline constexpr std::size_t kModelChars = 16;       // "Model (1 of 2)", "(2 of 2)"
inline constexpr std::size_t kSerialChars = 16;      // "Serial Number (1 of 2)", "(2 of 2)"
inline constexpr std::size_t kDeviceNameChars = 32;  // "Device Name (1 of 4)" .. "(4 of 4)"

// A payload shorter than its size is rejected; longer ones are read up to their size.
std::optional<Status> parse_status(ByteView p, ByteOrder order);
std::optional<BuildInfo> parse_build_info(ByteView p, ByteOrder order);
std::optional<RunningLimits> parse_running_limits(ByteView p, ByteOrder order);
Bytes encode_status(const Status& s, ByteOrder order);
Bytes encode_build_info(const BuildInfo& b, ByteOrder order);
Bytes encode_running_limits(const RunningLimits& l, ByteOrder order);

// "Set Run State": u16 speed, 0 = stop; big-endian as in the example (1000 = 03 E8).
Bytes encode_speed(std::uint16_t rpm);
std::optional<std::uint16_t> parse_speed(ByteView p);

}  // namespace drivegate::unicla
