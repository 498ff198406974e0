// The controller's alarm codes (OUTPUT, "Alarm codes"; ranges as read in specs README "fdc1"):
// the unified fault each stands for, whether the controller gave up retrying, and their labels.
// Pure.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "drivegate/common.h"
#include "drivegate/point.h"

namespace drivegate::fdc1 {

// One range of 16 codes, named by its first value (the document prints "16", "3247" for 32..47,
// ...: decimal ranges on multiples of 16, README "All numbers are decimal").
struct AlarmRange {
  std::uint8_t first;
  std::string_view name;     // the document's wording, and the alarm_code point's label
  std::string_view command;  // the simulator's `fault <command>`
  Fault fault;
  bool latched;  // an "(end of retries)" range: the controller stopped retrying
};

inline constexpr unsigned kAlarmRangeWidth = 16;
inline constexpr std::array<AlarmRange, 10> kAlarmRanges = {{
    {16, "battery out of limits", "battery", Fault::supply_fault, false},
    {32, "fan output overload", "fan", Fault::fan_fault, false},
    {48, "motor failed to start", "start", Fault::stall, false},
    {64, "motor overload", "overload", Fault::overload, false},
    {80, "overtemperature", "temperature", Fault::drive_over_temperature, false},
    {160, "fan output overload (end of retries)", "fan_eor", Fault::fan_fault, true},
    {176, "motor failed to start (end of retries)", "start_eor", Fault::stall, true},
    {192, "motor overload (end of retries)", "overload_eor", Fault::overload, true},
    {208, "overtemperature (end of retries)", "temperature_eor", Fault::drive_over_temperature,
     true},
    {240, "internal error", "internal", Fault::internal_error, false},
}};

struct Alarm {
  Fault fault = Fault::none;  // none for code 0
  bool latched = false;
  std::string_view name;
};

// 0 is no alarm; a code in no listed range (1..15, 96..159, 224..239) maps to Fault::other.
Alarm classify_alarm(std::uint8_t code);
// The range whose simulator command is `command`, if any.
std::optional<AlarmRange> find_alarm(std::string_view command);
// Labels of the alarm_code point: "none" for 0, then the first code of each range.
std::vector<Label> alarm_labels();

}  // namespace drivegate::fdc1
