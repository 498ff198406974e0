// `drivegate events` reads the daemon's history (GET /api/v1/events, docs/http.md) and prints one
// line per entry, as the journal would: time (UTC, ISO 8601, milliseconds), kind, device, what
// happened. Control characters a client put in a name (a certificate's role, an MQTT id) are
// shown as '?', never sent to the terminal. Pure: a JSON document in, lines out.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate::cli {

struct EventPage {
  std::uint64_t last_seq = 0;  // the daemon's newest entry: where --follow asks from next
  std::uint64_t dropped = 0;   // entries the history has pushed out since the daemon started
  std::int64_t started_ms = 0;  // when the daemon's history began: another value, a restart
  std::vector<std::string> lines;
  std::uint64_t newest_seq = 0;  // the newest entry printed (0: none)
};

// nullopt when `json` is not the events document.
std::optional<EventPage> event_lines(std::string_view json);

// "2026-11-27T11:30:02.123Z" of milliseconds since the epoch.
std::string utc_time(std::int64_t unix_ms);

}  // namespace drivegate::cli
