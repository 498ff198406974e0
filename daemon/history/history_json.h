// The history as JSON documents (docs/http.md): GET /api/v1/events and GET /api/v1/trends.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
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

// A page of events_json() made a slice at a time, so that the event loop can serve others
// between two slices (a page of 1000 entries is about 330 KB of JSON and milliseconds of work).
// Which entries, and the header's figures, are the log's when the page is begun; each entry is
// written as the log holds it when its slice comes: one pushed out meanwhile is left out, one a
// repeat updated shows the newer count.
class EventsPage {
 public:
  EventsPage(const EventLog& log, const EventFilter& filter);
  // Writes entries until the page has grown by `bytes` (or is whole): whether it is whole now.
  bool render(std::size_t bytes);
  [[nodiscard]] bool whole() const { return json_ != nullptr; }
  // The page, once whole.
  [[nodiscard]] const std::shared_ptr<const std::string>& json() const { return json_; }
  // The log's revision (EventLog::revision) when the page was begun.
  [[nodiscard]] std::uint64_t revision() const { return revision_; }

 private:
  const EventLog& log_;
  std::uint64_t revision_;
  std::vector<std::uint64_t> seqs_;  // the entries, oldest first
  std::size_t next_ = 0;             // the next one to write
  bool first_ = true;                // no entry written yet
  std::string out_;
  std::shared_ptr<const std::string> json_;
};

// The pages begun last, each kept while the log's revision stays the same: clients asking for the
// same page (sixteen screens on one status page, a scraper per address) cost one rendering
// between two changes of the log, not one each, and one being made is shared by all who ask.
class EventsPages {
 public:
  explicit EventsPages(const EventLog& log) : log_(log) {}
  std::shared_ptr<EventsPage> page(const EventFilter& filter);
  static constexpr std::size_t kPages = 8;  // distinct queries kept, the least recent dropped

 private:
  struct Kept {
    EventFilter filter;
    std::shared_ptr<EventsPage> page;
  };
  const EventLog& log_;
  std::deque<Kept> kept_;  // most recently asked first
};

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
