// The history as JSON documents (docs/http.md): GET /api/v1/events and GET /api/v1/trends.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "history/event_log.h"
#include "history/trend_store.h"

namespace drivegate {

// {"last_seq": N, "dropped": N, "started_ms": T, "capacity": N, "shelves": {"events":
// {"capacity", "size", "dropped"}, "commands": {...}, "refusals": {...}}, "events": [{"seq",
// "unix_ms", "kind", "device", "unit", "message", "fields": {...}}, ...]}, oldest first; last_seq
// is the log's, whatever matched; started_ms when the log began (a follower's sign of a
// restart); dropped and capacity are the shelves' together.
std::string events_json(const EventLog& log, const EventFilter& filter);

// Which trends: `name` empty for all, else the one key ("device:NAME", "bus:NAME"); rows at or
// after `since_ms`.
struct TrendFilter {
  std::string name;
  std::int64_t since_ms = 0;
};

// {"samples": N, "trends": [{"name", "series": [{"name", "unit"}], "t": [ms, ...],
// "values": [[series 0 ...], [series 1 ...]]}]}; an unknown value is null.
std::string trends_json(const TrendStore& store, const TrendFilter& filter);

}  // namespace drivegate
