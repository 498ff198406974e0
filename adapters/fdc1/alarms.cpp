#include "alarms.h"

namespace drivegate::fdc1 {

Alarm classify_alarm(std::uint8_t code) {
  if (code == 0) return {Fault::none, false, "none"};
  switch (code >> 4) {  // OUTPUT, "Alarm codes": one range per high nibble
    case 0x1:
      return {Fault::supply_fault, false, "battery out of limits"};
    case 0x2:
      return {Fault::fan_fault, false, "fan output overload"};
    case 0x3:
      return {Fault::stall, false, "motor failed to start"};
    case 0x4:
      return {Fault::overload, false, "motor overload"};
    case 0x5:
      return {Fault::drive_over_temperature, false, "overtemperature"};
    case 0xA:
      return {Fault::fan_fault, true, "fan output overload (end of retries)"};
    case 0xB:
      return {Fault::stall, true, "motor failed to start (end of retries)"};
    case 0xC:
      return {Fault::overload, true, "motor overload (end of retries)"};
    case 0xD:
      return {Fault::drive_over_temperature, true, "overtemperature (end of retries)"};
    case 0xF:
      return {Fault::internal_error, false, "internal error"};
    default:
      return {Fault::other, false, "undocumented alarm"};
  }
}

}  // namespace drivegate::fdc1
