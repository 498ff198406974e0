#include "faults.h"

namespace drivegate::fdc1 {

Alarm classify_alarm(std::uint8_t code) {
  if (code == 0) return {Fault::none, false, "none"};
  for (const AlarmRange& r : kAlarmRanges) {
    if (code >= r.first && unsigned{code} - r.first < kAlarmRangeWidth) {
      return {r.fault, r.latched, r.name};
    }
  }
  return {Fault::other, false, "undocumented alarm"};
}

std::optional<AlarmRange> find_alarm(std::string_view command) {
  for (const AlarmRange& r : kAlarmRanges) {
    if (r.command == command) return r;
  }
  return std::nullopt;
}

std::vector<Label> alarm_labels() {
  std::vector<Label> out{{"none", 0}};
  for (const AlarmRange& r : kAlarmRanges) out.push_back({std::string(r.name), r.first});
  return out;
}

}  // namespace drivegate::fdc1
