#include "history/event_log.h"

#include <algorithm>
#include <chrono>
#include <utility>

namespace drivegate {

namespace {

// At most kMaxText bytes, and no more memory than that: a string cut (or built with room to
// spare) gives the rest back.
void cut(std::string& s) {
  if (s.size() > kMaxText) {
    std::size_t n = kMaxText - 3;
    // Not inside a UTF-8 sequence: back to the byte that starts one.
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;
    s.resize(n);
    s += "...";
  }
  s.shrink_to_fit();
}

// The fields a repeat may differ in: how long the drive took, and the count of refusals held
// before it (command_audit.h), besides the repeat's own bookkeeping.
bool compared(const std::pair<std::string, std::string>& f) {
  return f.first != "took_ms" && f.first != "held" && f.first != "repeats" &&
         f.first != "last_ms";
}

bool same_but_time(const Event& a, const Event& b) {
  if (a.kind != EventKind::command || b.kind != EventKind::command || a.device != b.device ||
      a.unit != b.unit) {
    return false;
  }
  auto x = a.fields.begin();
  auto y = b.fields.begin();
  for (;;) {
    while (x != a.fields.end() && !compared(*x)) ++x;
    while (y != b.fields.end() && !compared(*y)) ++y;
    if (x == a.fields.end() || y == b.fields.end()) {
      return x == a.fields.end() && y == b.fields.end();
    }
    if (*x != *y) return false;
    ++x;
    ++y;
  }
}

void set_field(Event& e, const std::string& name, std::string value) {
  for (auto& [k, v] : e.fields) {
    if (k == name) {
      v = std::move(value);
      return;
    }
  }
  e.fields.emplace_back(name, std::move(value));
}

void count_repeat(Event& e, std::int64_t now_ms) {
  std::uint64_t n = 0;
  for (const char c : e.field("repeats")) n = n * 10 + static_cast<std::uint64_t>(c - '0');
  set_field(e, "repeats", std::to_string(n + 1));
  set_field(e, "last_ms", std::to_string(now_ms));
}

}  // namespace

std::int64_t EventLog::system_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

EventLog::EventLog(std::size_t capacity, WallClock wall)
    : capacity_(capacity), wall_(std::move(wall)), started_ms_(wall_()) {}

std::size_t EventLog::footprint(const Event& e) {
  std::size_t n = sizeof(Event) + e.device.capacity() + e.message.capacity() +
                  e.fields.capacity() * sizeof(e.fields[0]);
  for (const auto& [k, v] : e.fields) n += k.capacity() + v.capacity();
  return n;
}

void EventLog::fit(Event& e) {
  cut(e.device);
  cut(e.message);
  if (e.fields.size() > kMaxFields) e.fields.resize(kMaxFields);
  for (auto& [k, v] : e.fields) {
    cut(k);
    cut(v);
  }
  e.fields.shrink_to_fit();
}

Event* EventLog::entry(std::uint64_t seq) {
  return const_cast<Event*>(std::as_const(*this).find(seq));  // this log's own, not const
}

std::uint64_t EventLog::add(Event e) {
  ++revision_;
  e.seq = next_seq_++;
  e.unix_ms = wall_();
  fit(e);
  // The device's newest, kept aside for repeat() (its size is bounded like an entry's, and there
  // is one per configured device).
  auto it = newest_.find(e.device);
  if (it == newest_.end()) {
    newest_.emplace(e.device, e);
  } else {
    it->second = e;
  }
  if (capacity_ == 0) return e.seq;  // [history] events = 0: nothing kept
  if (entries_.size() == capacity_) {
    bytes_ -= footprint(entries_.front());
    entries_.pop_front();
    ++dropped_;
  }
  bytes_ += footprint(e);
  entries_.push_back(std::move(e));
  return entries_.back().seq;
}

bool EventLog::repeat(const Event& e) {
  Event fitted = e;
  fit(fitted);
  const auto it = newest_.find(fitted.device);
  if (it == newest_.end() || !same_but_time(it->second, fitted)) return false;
  const std::int64_t now = wall_();
  ++revision_;
  count_repeat(it->second, now);
  if (Event* kept = entry(it->second.seq)) {
    bytes_ -= footprint(*kept);
    count_repeat(*kept, now);
    bytes_ += footprint(*kept);
  }
  return true;
}

const Event* EventLog::find(std::uint64_t seq) const {
  if (entries_.empty() || seq < entries_.front().seq || seq > entries_.back().seq) return nullptr;
  return &entries_[seq - entries_.front().seq];
}

std::vector<std::uint64_t> EventLog::matching(const EventFilter& filter) const {
  const std::size_t limit = std::min(filter.limit, kMaxQuery);
  std::vector<std::uint64_t> out;
  if (limit == 0) return out;
  const auto matches = [&](const Event& e) {
    return (filter.device.empty() || e.device == filter.device) &&
           (!filter.kind || e.kind == *filter.kind) && e.unix_ms >= filter.since_ms;
  };
  if (filter.after_seq > 0) {
    // A follower: the oldest entries after the one it has, so that it misses none.
    auto it = std::find_if(entries_.begin(), entries_.end(),
                           [&](const Event& e) { return e.seq > filter.after_seq; });
    for (; it != entries_.end() && out.size() < limit; ++it) {
      if (matches(*it)) out.push_back(it->seq);
    }
    return out;
  }
  // Newest first until the limit, then turned oldest first.
  for (auto it = entries_.rbegin(); it != entries_.rend() && out.size() < limit; ++it) {
    if (matches(*it)) out.push_back(it->seq);
  }
  std::reverse(out.begin(), out.end());
  return out;
}

std::vector<Event> EventLog::query(const EventFilter& filter) const {
  std::vector<Event> out;
  for (const std::uint64_t seq : matching(filter)) out.push_back(*find(seq));
  return out;
}

}  // namespace drivegate
