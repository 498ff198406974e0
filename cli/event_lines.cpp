#include "event_lines.h"

#include <charconv>
#include <chrono>
#include <cstdio>
#include <ctime>

#include "json_reader.h"

namespace drivegate::cli {

namespace {

template <class T>
bool number(Reader& r, T& out) {
  const auto t = r.token();
  if (!t) return false;
  const auto [p, ec] = std::from_chars(t->data(), t->data() + t->size(), out);
  return ec == std::errc{} && p == t->data() + t->size();
}

// One entry: {"seq", "unix_ms", "kind", "device", "unit", "message", "fields": {...}}.
bool entry(Reader& r, std::uint64_t& seq, std::string& line) {
  if (!r.at('{')) return false;
  std::int64_t unix_ms = 0;
  std::string kind;
  std::string device;
  std::string message;
  if (r.at('}')) return false;
  do {
    const auto key = r.string();
    if (!key || !r.at(':')) return false;
    bool ok = true;
    if (*key == "seq") {
      ok = number(r, seq);
    } else if (*key == "unix_ms") {
      ok = number(r, unix_ms);
    } else if (*key == "kind" || *key == "device" || *key == "message") {
      auto v = r.string();
      ok = v.has_value();
      if (ok) (*key == "kind" ? kind : *key == "device" ? device : message) = std::move(*v);
    } else {
      ok = r.skip();
    }
    if (!ok) return false;
  } while (r.at(','));
  if (!r.at('}')) return false;
  line = utc_time(unix_ms) + "  " + kind;
  line.resize(std::max<std::size_t>(line.size(), 24 + 2 + 16), ' ');
  line += "  " + (device.empty() ? std::string("-") : device) + "  " + message;
  for (char& c : line) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7F) c = '?';
  }
  return true;
}

}  // namespace

std::string utc_time(std::int64_t unix_ms) {
  const auto secs = static_cast<std::time_t>(unix_ms / 1000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[64];  // room for any int the format may be given
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>(unix_ms % 1000));
  return buf;
}

std::optional<EventPage> event_lines(std::string_view json) {
  Reader r(json);
  EventPage page;
  bool saw_events = false;
  if (!r.at('{') || r.at('}')) return std::nullopt;
  do {
    const auto key = r.string();
    if (!key || !r.at(':')) return std::nullopt;
    if (*key == "last_seq") {
      if (!number(r, page.last_seq)) return std::nullopt;
    } else if (*key == "started_ms") {
      if (!number(r, page.started_ms)) return std::nullopt;
    } else if (*key == "dropped") {
      if (!number(r, page.dropped)) return std::nullopt;
    } else if (*key == "events") {
      saw_events = true;
      if (!r.at('[')) return std::nullopt;
      if (r.at(']')) continue;
      do {
        std::uint64_t seq = 0;
        std::string line;
        if (!entry(r, seq, line)) return std::nullopt;
        page.lines.push_back(std::move(line));
        page.newest_seq = std::max(page.newest_seq, seq);
      } while (r.at(','));
      if (!r.at(']')) return std::nullopt;
    } else if (!r.skip()) {
      return std::nullopt;
    }
  } while (r.at(','));
  if (!r.at('}') || !saw_events) return std::nullopt;
  return page;
}

}  // namespace drivegate::cli
