// The controller's alarm codes (OUTPUT, "Alarm codes"; ranges as read in specs README "fdc1").
// Pure.
#pragma once

#include <cstdint>
#include <string_view>

#include "drivegate/common.h"

namespace drivegate::fdc1 {

struct Alarm {
  Fault fault = Fault::none;  // the unified fault, none for code 0
  bool latched = false;       // an "(end of retries)" range: the controller stopped retrying
  std::string_view name;      // the document's wording
};

// Codes are ranges of 16 named by their first value: 16..31 battery out of limits, 32..47 fan
// output overload, 48..63 motor failed to start, 64..79 motor overload, 80..95 overtemperature,
// 160..175 / 176..191 / 192..207 / 208..223 the same "(end of retries)", 240..255 internal error.
// 0 is no alarm; codes in no listed range map to Fault::other.
Alarm classify_alarm(std::uint8_t code);

}  // namespace drivegate::fdc1
