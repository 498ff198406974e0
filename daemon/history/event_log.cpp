#include "history/event_log.h"

#include <algorithm>
#include <chrono>
#include <utility>

#include "gateway/source.h"

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

// The fields a repeat may differ in: how long the drive took, besides the repeat's own
// bookkeeping.
bool compared(const std::pair<std::string, std::string>& f) {
  return f.first != "took_ms" && f.first != "repeats" && f.first != "last_ms";
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

bool by_seq(const Event& e, std::uint64_t seq) {
  return e.seq < seq;
}

}  // namespace

Shelf shelf_of(const Event& e) {
  if (e.kind != EventKind::command) return Shelf::events;
  const std::string_view source = e.field("source");
  if (source == to_string(SourceKind::failsafe) || source == to_string(SourceKind::shutdown) ||
      source == to_string(SourceKind::gateway)) {
    return Shelf::events;
  }
  return e.field("result") == "ok" ? Shelf::commands : Shelf::refusals;
}

std::int64_t EventLog::system_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

EventLog::EventLog(HistoryBounds bounds, WallClock wall)
    : bounds_(bounds), wall_(std::move(wall)), started_ms_(wall_()) {}

EventLog::EventLog(std::size_t each, WallClock wall)
    : EventLog(HistoryBounds{each, each, each}, std::move(wall)) {}

std::size_t EventLog::size() const {
  std::size_t n = 0;
  for (const auto& s : shelves_) n += s.size();
  return n;
}

std::size_t EventLog::capacity() const {
  return bounds_.events + bounds_.commands + bounds_.refusals;
}

std::uint64_t EventLog::dropped() const {
  std::uint64_t n = 0;
  for (const auto d : dropped_) n += d;
  return n;
}

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

Event* EventLog::entry(const Event& like) {
  auto& shelf = shelves_[static_cast<std::size_t>(shelf_of(like))];
  const auto it = std::lower_bound(shelf.begin(), shelf.end(), like.seq, by_seq);
  return it != shelf.end() && it->seq == like.seq ? &*it : nullptr;
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
  const Shelf s = shelf_of(e);
  const std::size_t capacity = bounds_.of(s);
  if (capacity == 0) return e.seq;  // [history] NAME = 0: nothing kept there
  auto& shelf = shelves_[static_cast<std::size_t>(s)];
  if (shelf.size() >= capacity) {
    bytes_ -= footprint(shelf.front());
    shelf.pop_front();
    ++dropped_[static_cast<std::size_t>(s)];
  }
  bytes_ += footprint(e);
  shelf.push_back(std::move(e));
  return shelf.back().seq;
}

bool EventLog::repeat(const Event& e) {
  Event fitted = e;
  fit(fitted);
  const auto it = newest_.find(fitted.device);
  if (it == newest_.end() || !same_but_time(it->second, fitted)) return false;
  const std::int64_t now = wall_();
  ++revision_;
  count_repeat(it->second, now);
  if (Event* kept = entry(it->second)) {
    bytes_ -= footprint(*kept);
    count_repeat(*kept, now);
    bytes_ += footprint(*kept);
  }
  return true;
}

void EventLog::interrupt(std::string_view device) {
  if (const auto it = newest_.find(device); it != newest_.end()) newest_.erase(it);
}

const Event* EventLog::find(std::uint64_t seq) const {
  for (const auto& shelf : shelves_) {
    const auto it = std::lower_bound(shelf.begin(), shelf.end(), seq, by_seq);
    if (it != shelf.end() && it->seq == seq) return &*it;
  }
  return nullptr;
}

std::vector<Event> EventLog::query(const EventFilter& filter) const {
  std::vector<Event> out;
  for (const std::uint64_t seq : matching(filter)) out.push_back(*find(seq));
  return out;
}

std::vector<std::uint64_t> EventLog::matching(const EventFilter& filter) const {
  const std::size_t limit = std::min(filter.limit, kMaxQuery);
  std::vector<std::uint64_t> out;
  if (limit == 0) return out;
  const auto matches = [&](const Event& e) {
    return (filter.device.empty() || e.device == filter.device) &&
           (!filter.kind || e.kind == *filter.kind) && e.unix_ms >= filter.since_ms;
  };
  // Only the events' shelf holds anything but commands.
  const std::size_t shelves =
      filter.kind && *filter.kind != EventKind::command ? 1 : shelves_.size();
  if (filter.after_seq > 0) {
    // A follower: the oldest entries after the one it has, so that it misses none; the shelves
    // merged in sequence.
    std::array<std::deque<Event>::const_iterator, kShelfNames.size()> at{};
    for (std::size_t s = 0; s < shelves; ++s) {
      at[s] = std::upper_bound(shelves_[s].begin(), shelves_[s].end(), filter.after_seq,
                               [](std::uint64_t seq, const Event& e) { return seq < e.seq; });
    }
    while (out.size() < limit) {
      std::size_t next = shelves;
      for (std::size_t s = 0; s < shelves; ++s) {
        if (at[s] != shelves_[s].end() && (next == shelves || at[s]->seq < at[next]->seq)) {
          next = s;
        }
      }
      if (next == shelves) break;
      if (matches(*at[next])) out.push_back(at[next]->seq);
      ++at[next];
    }
    return out;
  }
  // Newest first until the limit, the shelves merged in sequence, then turned oldest first.
  std::array<std::deque<Event>::const_reverse_iterator, kShelfNames.size()> at{};
  for (std::size_t s = 0; s < shelves; ++s) at[s] = shelves_[s].rbegin();
  while (out.size() < limit) {
    std::size_t next = shelves;
    for (std::size_t s = 0; s < shelves; ++s) {
      if (at[s] != shelves_[s].rend() && (next == shelves || at[s]->seq > at[next]->seq)) {
        next = s;
      }
    }
    if (next == shelves) break;
    if (matches(*at[next])) out.push_back(at[next]->seq);
    ++at[next];
  }
  std::reverse(out.begin(), out.end());
  return out;
}

}  // namespace drivegate
