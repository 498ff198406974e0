#include "history/history_json.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>

#include "base/json.h"

namespace drivegate {

namespace {

void append_number(std::string& out, std::int64_t v) {
  out += std::to_string(v);
}

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

EventsPage::EventsPage(const EventLog& log, const EventFilter& filter)
    : log_(log), revision_(log.revision()), seqs_(log.matching(filter)) {
  out_.reserve(128 + seqs_.size() * 400);
  out_ += "{\"last_seq\":";
  append_number(out_, static_cast<std::int64_t>(log.last_seq()));
  out_ += ",\"dropped\":";
  append_number(out_, static_cast<std::int64_t>(log.dropped()));
  out_ += ",\"started_ms\":";
  append_number(out_, log.started_ms());
  out_ += ",\"capacity\":";
  append_number(out_, static_cast<std::int64_t>(log.capacity()));
  out_ += ",\"shelves\":{";
  for (std::size_t i = 0; i < kShelfNames.size(); ++i) {
    const auto shelf = static_cast<Shelf>(i);
    if (i > 0) out_ += ',';
    append_json_string(out_, kShelfNames[i]);
    out_ += ":{\"capacity\":";
    append_number(out_, static_cast<std::int64_t>(log.capacity(shelf)));
    out_ += ",\"size\":";
    append_number(out_, static_cast<std::int64_t>(log.size(shelf)));
    out_ += ",\"dropped\":";
    append_number(out_, static_cast<std::int64_t>(log.dropped(shelf)));
    out_ += '}';
  }
  out_ += "},\"events\":[";
}

bool EventsPage::render(std::size_t bytes) {
  if (json_) return true;
  const std::size_t until = out_.size() + std::min(bytes, SIZE_MAX - out_.size());
  while (next_ < seqs_.size() && out_.size() < until) {
    const Event* e = log_.find(seqs_[next_++]);
    if (e == nullptr) continue;  // pushed out since the page was begun
    if (!first_) out_ += ',';
    first_ = false;
    out_ += "{\"seq\":";
    append_number(out_, static_cast<std::int64_t>(e->seq));
    out_ += ",\"unix_ms\":";
    append_number(out_, e->unix_ms);
    out_ += ",\"kind\":";
    append_json_string(out_, to_string(e->kind));
    out_ += ",\"device\":";
    append_json_string(out_, e->device);
    out_ += ",\"unit\":";
    append_number(out_, e->unit);
    out_ += ",\"message\":";
    append_json_string(out_, e->message);
    out_ += ",\"fields\":{";
    bool first_field = true;
    for (const auto& [k, v] : e->fields) {
      if (!first_field) out_ += ',';
      first_field = false;
      append_json_string(out_, k);
      out_ += ':';
      append_json_string(out_, v);
    }
    out_ += "}}";
  }
  if (next_ < seqs_.size()) return false;
  out_ += "]}";
  json_ = std::make_shared<const std::string>(std::move(out_));
  return true;
}

std::string events_json(const EventLog& log, const EventFilter& filter) {
  EventsPage page(log, filter);
  page.render(SIZE_MAX);
  return *page.json();
}

std::shared_ptr<EventsPage> EventsPages::page(const EventFilter& filter) {
  const auto same = [&](const Kept& k) {
    const EventFilter& f = k.filter;
    return f.device == filter.device && f.kind == filter.kind && f.since_ms == filter.since_ms &&
           f.after_seq == filter.after_seq && f.limit == filter.limit;
  };
  const auto it = std::find_if(kept_.begin(), kept_.end(), same);
  std::shared_ptr<EventsPage> page;
  if (it != kept_.end()) {
    if (it->page->revision() == log_.revision()) page = std::move(it->page);
    kept_.erase(it);
  }
  if (!page) page = std::make_shared<EventsPage>(log_, filter);
  kept_.push_front({filter, page});
  if (kept_.size() > kPages) kept_.pop_back();
  return page;
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
