#include "history/event_log.h"

#include <algorithm>
#include <chrono>

namespace drivegate {

namespace {

// How far back repeat() looks for the device's newest entry: past it, the entry is added anew.
constexpr std::size_t kRepeatLookback = 64;

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

bool same_but_time(const Event& a, const Event& b) {
  if (a.kind != b.kind || a.device != b.device || a.unit != b.unit) return false;
  const auto kept = [](const auto& f) {
    return f.first != "took_ms" && f.first != "repeats" && f.first != "last_ms";
  };
  std::vector<std::pair<std::string, std::string>> x;
  std::vector<std::pair<std::string, std::string>> y;
  std::copy_if(a.fields.begin(), a.fields.end(), std::back_inserter(x), kept);
  std::copy_if(b.fields.begin(), b.fields.end(), std::back_inserter(y), kept);
  return x == y;
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

}  // namespace

std::int64_t EventLog::system_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

EventLog::EventLog(std::size_t capacity, WallClock wall)
    : capacity_(capacity), wall_(std::move(wall)) {}

std::size_t EventLog::footprint(const Event& e) {
  std::size_t n = sizeof(Event) + e.device.capacity() + e.message.capacity() +
                  e.fields.capacity() * sizeof(e.fields[0]);
  for (const auto& [k, v] : e.fields) n += k.capacity() + v.capacity();
  return n;
}

std::uint64_t EventLog::add(Event e) {
  e.seq = next_seq_++;
  if (capacity_ == 0) return e.seq;  // [history] events = 0: nothing kept
  e.unix_ms = wall_();
  cut(e.device);
  cut(e.message);
  if (e.fields.size() > kMaxFields) e.fields.resize(kMaxFields);
  for (auto& [k, v] : e.fields) {
    cut(k);
    cut(v);
  }
  e.fields.shrink_to_fit();
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
  std::size_t looked = 0;
  for (auto it = entries_.rbegin(); it != entries_.rend() && looked < kRepeatLookback;
       ++it, ++looked) {
    if (it->device != e.device) continue;
    if (!same_but_time(*it, e)) return false;
    bytes_ -= footprint(*it);
    const std::string_view was = it->field("repeats");
    std::uint64_t n = 0;
    for (const char c : was) n = n * 10 + static_cast<std::uint64_t>(c - '0');
    set_field(*it, "repeats", std::to_string(n + 1));
    set_field(*it, "last_ms", std::to_string(wall_()));
    bytes_ += footprint(*it);
    return true;
  }
  return false;
}

std::vector<Event> EventLog::query(const EventFilter& filter) const {
  const std::size_t limit = std::min(filter.limit, kMaxQuery);
  std::vector<Event> out;
  if (limit == 0) return out;
  // Newest first until the limit, then turned oldest first.
  for (auto it = entries_.rbegin(); it != entries_.rend() && out.size() < limit; ++it) {
    const Event& e = *it;
    if (e.seq <= filter.after_seq) break;  // seq only grows towards the back
    if (!filter.device.empty() && e.device != filter.device) continue;
    if (filter.kind && e.kind != *filter.kind) continue;
    if (e.unix_ms < filter.since_ms) continue;
    out.push_back(e);
  }
  std::reverse(out.begin(), out.end());
  return out;
}

}  // namespace drivegate
