#include "history/command_fold.h"

#include <algorithm>
#include <cctype>
#include <charconv>

#include "history/command_audit.h"
#include "history/event_log.h"

namespace drivegate {

namespace {

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

bool is_number(std::string_view s) {
  double v = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc{} && end == s.data() + s.size();
}

// At most kMaxText bytes: what a summary keeps of a record is bounded like a history entry.
std::string bounded(std::string_view s) {
  return std::string(s.substr(0, std::min(s.size(), kMaxText)));
}

}  // namespace

std::string client_address(std::string_view client) {
  if (client.starts_with('[')) {  // "[v6]:port"
    const auto close = client.find(']');
    return std::string(close == std::string_view::npos ? client : client.substr(0, close + 1));
  }
  const auto colon = client.rfind(':');
  if (colon == std::string_view::npos || !all_digits(client.substr(colon + 1))) {
    return std::string(client);
  }
  // "a.b.c.d:port", or an IPv6 address and its port without brackets ("::1:502", as the Modbus
  // TCP server says them).
  return std::string(client.substr(0, colon));
}

std::string fold_points(std::string_view points) {
  // Registers or a PDU as they came: "TABLE FIRST[..LAST] = V ..." or "pdu FC ...".
  const auto space = points.find(' ');
  const std::string_view first = points.substr(0, space);
  if (first == "pdu") return std::string(points.substr(0, std::min<std::size_t>(points.size(), 6)));
  if (std::find(kTableNames.begin(), kTableNames.end(), first) != kTableNames.end() &&
      space != std::string_view::npos && space + 1 < points.size() &&
      std::isdigit(static_cast<unsigned char>(points[space + 1])) != 0) {
    return std::string(first);
  }
  // "name=value ...": a number's value left out. A string value's words past its first are part
  // of it, not points.
  std::string out;
  std::size_t at = 0;
  while (at < points.size()) {
    auto end = points.find(' ', at);
    if (end == std::string_view::npos) end = points.size();
    const std::string_view word = points.substr(at, end - at);
    at = end + 1;
    const auto eq = word.find('=');
    if (eq == std::string_view::npos || eq == 0) continue;
    if (!out.empty()) out += ' ';
    out += is_number(word.substr(eq + 1)) ? word.substr(0, eq) : word;
    if (out.size() > kMaxText) break;
  }
  return bounded(out);
}

CommandFold::CommandFold(FoldLimits limits)
    : limits_(limits),
      overall_(limits.overall_burst, std::chrono::duration_cast<net::TokenBucket::Clock::duration>(
                                         std::chrono::seconds(1)) /
                                         std::max(1U, limits.overall_per_second)) {}

CommandFold::Key CommandFold::key_for(const CommandRecord& r) const {
  Key k{.spread = FoldSpread::points,
        .source = r.source.kind,
        .listener = bounded(r.source.listener),
        .client = bounded(client_address(r.source.client)),
        .device = r.device,
        .unit = r.unit,
        .points = fold_points(r.points),
        .result = r.result};
  if (keys_.contains(k)) return k;
  const ClientKey client{k.source, k.listener, k.client};
  const auto held = per_client_.find(client);
  const bool client_full = held != per_client_.end() && held->second >= limits_.keys_per_client;
  if (!client_full && keys_.size() < limits_.keys) return k;
  k.device.clear();
  k.unit = 0;
  k.points.clear();
  k.spread = FoldSpread::client;
  if (keys_.contains(k) || keys_.size() < limits_.keys) return k;
  // Every table full: the source kind's own, beside the bound (one per kind and result).
  k.listener.clear();
  k.client.clear();
  k.spread = FoldSpread::source;
  return k;
}

bool CommandFold::admit(const CommandRecord& r, TimePoint now, std::int64_t wall_ms) {
  const Key key = key_for(r);
  auto it = keys_.find(key);
  if (it == keys_.end()) {
    it = keys_
             .emplace(key, Entry{.allowance = net::TokenBucket(limits_.burst, limits_.refill),
                                 .folding = std::nullopt})
             .first;
    if (key.spread == FoldSpread::points) ++per_client_[{key.source, key.listener, key.client}];
  }
  Entry& e = it->second;
  if (!e.folding && e.allowance.ready(now) && overall_.ready(now)) {
    (void)e.allowance.take(now);
    (void)overall_.take(now);
    return true;
  }
  if (!e.folding) {
    FoldSummary first;
    first.spread = key.spread;
    first.source = key.source;
    first.listener = key.listener;
    first.client = key.client;
    first.device = key.device;
    first.unit = key.unit;
    first.points = key.points;
    first.result = key.result;
    first.since_ms = wall_ms;
    e.folding = Folding{.since = now, .summary = std::move(first)};
  }
  FoldSummary& s = e.folding->summary;
  ++s.folded;
  s.last_ms = wall_ms;
  s.last_source = Source{.kind = r.source.kind,
                         .listener = bounded(r.source.listener),
                         .client = bounded(r.source.client),
                         .subject = bounded(r.source.subject),
                         .role = bounded(r.source.role)};
  s.last_device = r.device;
  s.last_unit = r.unit;
  s.last_points = bounded(r.points);
  s.last_why = bounded(r.why);
  return false;
}

std::vector<FoldSummary> CommandFold::due(TimePoint now, bool all) {
  std::vector<std::pair<TimePoint, FoldSummary>> out;
  for (auto& [key, e] : keys_) {
    if (!e.folding || (!all && now - e.folding->since < limits_.interval)) continue;
    out.emplace_back(e.folding->since, std::move(e.folding->summary));
    e.folding.reset();
    // Still busy, it folds on at its next record: one summary an interval, not a burst each.
    e.allowance.drain(now);
  }
  forget_idle(now);
  std::stable_sort(out.begin(), out.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<FoldSummary> summaries;
  summaries.reserve(out.size());
  for (auto& [since, s] : out) summaries.push_back(std::move(s));
  return summaries;
}

void CommandFold::forget_idle(TimePoint now) {
  for (auto it = keys_.begin(); it != keys_.end();) {
    if (it->second.folding || !it->second.allowance.full(now)) {
      ++it;
      continue;
    }
    if (it->first.spread == FoldSpread::points) {
      const auto c = per_client_.find({it->first.source, it->first.listener, it->first.client});
      if (c != per_client_.end() && --c->second == 0) per_client_.erase(c);
    }
    it = keys_.erase(it);
  }
}

}  // namespace drivegate
