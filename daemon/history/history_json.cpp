#include "history/history_json.h"

#include <charconv>
#include <cmath>

#include "base/json.h"

namespace drivegate {

namespace {

void append_number(std::string& out, std::int64_t v) { out += std::to_string(v); }

void append_float(std::string& out, float v) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

}  // namespace

std::string events_json(const EventLog& log, const EventFilter& filter) {
  const std::vector<Event> events = log.query(filter);
  std::string out;
  out.reserve(128 + events.size() * 400);
  out += "{\"last_seq\":";
  append_number(out, static_cast<std::int64_t>(log.last_seq()));
  out += ",\"dropped\":";
  append_number(out, static_cast<std::int64_t>(log.dropped()));
  out += ",\"started_ms\":";
  append_number(out, log.started_ms());
  out += ",\"capacity\":";
  append_number(out, static_cast<std::int64_t>(log.capacity()));
  out += ",\"shelves\":{";
  for (std::size_t i = 0; i < kShelfNames.size(); ++i) {
    const auto shelf = static_cast<Shelf>(i);
    if (i > 0) out += ',';
    append_json_string(out, kShelfNames[i]);
    out += ":{\"capacity\":";
    append_number(out, static_cast<std::int64_t>(log.capacity(shelf)));
    out += ",\"size\":";
    append_number(out, static_cast<std::int64_t>(log.size(shelf)));
    out += ",\"dropped\":";
    append_number(out, static_cast<std::int64_t>(log.dropped(shelf)));
    out += '}';
  }
  out += "},\"events\":[";
  bool first = true;
  for (const Event& e : events) {
    if (!first) out += ',';
    first = false;
    out += "{\"seq\":";
    append_number(out, static_cast<std::int64_t>(e.seq));
    out += ",\"unix_ms\":";
    append_number(out, e.unix_ms);
    out += ",\"kind\":";
    append_json_string(out, to_string(e.kind));
    out += ",\"device\":";
    append_json_string(out, e.device);
    out += ",\"unit\":";
    append_number(out, e.unit);
    out += ",\"message\":";
    append_json_string(out, e.message);
    out += ",\"fields\":{";
    bool first_field = true;
    for (const auto& [k, v] : e.fields) {
      if (!first_field) out += ',';
      first_field = false;
      append_json_string(out, k);
      out += ':';
      append_json_string(out, v);
    }
    out += "}}";
  }
  out += "]}";
  return out;
}

std::string trends_json(const TrendStore& store, const TrendFilter& filter) {
  std::string out;
  out += "{\"samples\":";
  append_number(out, static_cast<std::int64_t>(store.samples()));
  out += ",\"trends\":[";
  bool first = true;
  for (const auto& [name, trend] : store.trends()) {
    if (!filter.name.empty() && name != filter.name) continue;
    std::size_t from = 0;
    while (from < trend.size() && trend.time(from) < filter.since_ms) ++from;
    if (!first) out += ',';
    first = false;
    out += "{\"name\":";
    append_json_string(out, name);
    out += ",\"series\":[";
    for (std::size_t s = 0; s < trend.series().size(); ++s) {
      if (s > 0) out += ',';
      out += "{\"name\":";
      append_json_string(out, trend.series()[s].name);
      out += ",\"unit\":";
      append_json_string(out, trend.series()[s].unit);
      out += '}';
    }
    out += "],\"t\":[";
    for (std::size_t i = from; i < trend.size(); ++i) {
      if (i > from) out += ',';
      append_number(out, trend.time(i));
    }
    out += "],\"values\":[";
    for (std::size_t s = 0; s < trend.series().size(); ++s) {
      if (s > 0) out += ',';
      out += '[';
      for (std::size_t i = from; i < trend.size(); ++i) {
        if (i > from) out += ',';
        append_float(out, trend.value(i, s));
      }
      out += ']';
    }
    out += "]}";
  }
  out += "]}";
  return out;
}

}  // namespace drivegate
