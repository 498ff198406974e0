#include "history/trend_store.h"

#include <algorithm>

namespace drivegate {

Trend::Trend(std::vector<TrendSeries> series, std::size_t samples)
    : series_(std::move(series)),
      times_(std::max<std::size_t>(samples, 1), 0),
      values_(times_.size() * series_.size(), 0.0F) {}

void Trend::add(std::int64_t unix_ms, std::span<const float> values) {
  std::size_t at = 0;
  if (count_ < times_.size()) {
    at = (head_ + count_) % times_.size();
    ++count_;
  } else {
    at = head_;  // the oldest row goes
    head_ = (head_ + 1) % times_.size();
  }
  times_[at] = unix_ms;
  const std::size_t n = series_.size();
  for (std::size_t s = 0; s < n; ++s) {
    values_[at * n + s] = s < values.size() ? values[s] : 0.0F;
  }
}

std::size_t Trend::memory_bytes() const {
  std::size_t b = sizeof(*this) + times_.capacity() * sizeof(std::int64_t) +
                  values_.capacity() * sizeof(float) + series_.capacity() * sizeof(TrendSeries);
  for (const auto& s : series_) b += s.name.capacity() + s.unit.capacity();
  return b;
}

void TrendStore::add(std::string_view key, const std::vector<TrendSeries>& series,
                     std::int64_t unix_ms, std::span<const float> values) {
  auto it = trends_.find(key);
  if (it != trends_.end() && it->second.series() != series) {
    trends_.erase(it);
    it = trends_.end();
  }
  if (it == trends_.end()) it = trends_.emplace(std::string(key), Trend(series, samples_)).first;
  it->second.add(unix_ms, values);
}

void TrendStore::keep_only(const std::vector<std::string>& keys) {
  std::erase_if(trends_, [&](const auto& kv) {
    return std::find(keys.begin(), keys.end(), kv.first) == keys.end();
  });
}

std::size_t TrendStore::memory_bytes() const {
  std::size_t b = sizeof(*this);
  for (const auto& [k, t] : trends_) b += k.capacity() + t.memory_bytes() + 64;  // map node
  return b;
}

}  // namespace drivegate
