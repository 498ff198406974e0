// One entry of the daemon's history (event_log.h): a command and what came of it
// (command_audit.h), or an event that matters to the plant. The same words go to the journal, to
// GET /api/v1/events and to `drivegate events`.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace drivegate {

enum class EventKind : std::uint8_t {
  command,           // a write, from any northbound or the gateway itself, and its result
  fault_raised,      // the drive's unified fault changed to a fault (label, native code)
  fault_cleared,     // ... and back to none
  comm_lost,         // the drive stopped answering (docs/safety.md, comm_lost)
  comm_restored,     // ... and answers again
  failsafe_tripped,  // the PLC stopped writing: the failsafe acted (latched)
  failsafe_cleared,  // a run command from the PLC reset it
  drive_started,     // the drive reports running
  drive_stopped,     // ... and no longer does
  reload,            // the configuration was reloaded (what changed)
  listener,          // a northbound listener opened, closed, or waits for a restart
  mqtt,              // the MQTT session changed state (online, offline, ...)
};

// Their names in the JSON, the query (?kind=) and the journal (EVENT=), in enum order.
inline constexpr std::array<std::string_view, 12> kEventKindNames = {
    "command",   "fault_raised",  "fault_cleared", "comm_lost", "comm_restored", "failsafe_tripped",
    "failsafe_cleared", "drive_started", "drive_stopped", "reload", "listener", "mqtt"};
constexpr std::string_view to_string(EventKind k) {
  return kEventKindNames.at(static_cast<std::size_t>(k));
}
// The kind of that name, if there is one.
inline bool parse_event_kind(std::string_view name, EventKind& out) {
  for (std::size_t i = 0; i < kEventKindNames.size(); ++i) {
    if (kEventKindNames[i] == name) {
      out = static_cast<EventKind>(i);
      return true;
    }
  }
  return false;
}

struct Event {
  std::uint64_t seq = 0;     // 1, 2, ... in the order recorded (EventLog::add sets it)
  std::int64_t unix_ms = 0;  // when, milliseconds since the epoch (EventLog::add sets it)
  EventKind kind = EventKind::command;
  std::string device;        // the device it concerns; empty: the gateway's own
  std::uint8_t unit = 0;     // the device's Modbus unit id; 0: none
  std::string message;       // one line, as the journal says it
  // What else it says, by name (lower case: "source", "client", "result", "fault", ...); the
  // journal's fields are these names upper-cased.
  std::vector<std::pair<std::string, std::string>> fields;

  // The value of field `name`, or "".
  [[nodiscard]] std::string_view field(std::string_view name) const {
    for (const auto& [k, v] : fields) {
      if (k == name) return v;
    }
    return {};
  }
};

}  // namespace drivegate
