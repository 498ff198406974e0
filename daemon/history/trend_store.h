// Trends: a short history of numbers per drive (speed, setpoint and the points its adapter marks
// PointSpec::trend: currents, pressures, temperatures, power) and per bus (line utilisation),
// sampled by the daemon once a second (app/trend_sampler.h), served at /api/v1/trends and drawn
// on the status page. Pure: the caller says what time it is.
//
// Memory: each trend is a ring of `samples` rows of one time (8 bytes) and one float per series
// (4 bytes): with the default 600 samples (10 minutes at 1 s) a drive with speed, setpoint and
// four adapter points takes 600 x (8 + 6 x 4) = 19.2 KB, plus its names; bench/history.sh
// measures 32 buses x 4 drives.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate {

inline constexpr std::size_t kTrendSamples = 600;  // 10 minutes at one sample a second

struct TrendSeries {
  std::string name;  // "speed_rpm", "current_a", "utilisation"
  std::string unit;  // "rpm", "A", "%"
  bool operator==(const TrendSeries&) const = default;
};

// One drive's (or bus's) series, sampled together.
class Trend {
 public:
  Trend(std::vector<TrendSeries> series, std::size_t samples);

  // One row: a value per series, in order (NaN: unknown then, e.g. comm lost).
  void add(std::int64_t unix_ms, std::span<const float> values);
  [[nodiscard]] const std::vector<TrendSeries>& series() const { return series_; }
  [[nodiscard]] std::size_t size() const { return count_; }
  // Row i, oldest first (i < size()).
  [[nodiscard]] std::int64_t time(std::size_t i) const { return times_[slot(i)]; }
  [[nodiscard]] float value(std::size_t i, std::size_t series) const {
    return values_[slot(i) * series_.size() + series];
  }
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  [[nodiscard]] std::size_t slot(std::size_t i) const { return (head_ + i) % times_.size(); }

  std::vector<TrendSeries> series_;
  std::vector<std::int64_t> times_;
  std::vector<float> values_;
  std::size_t head_ = 0;  // the oldest row
  std::size_t count_ = 0;
};

// Every trend by name ("device:washer-1", "bus:line-a").
class TrendStore {
 public:
  explicit TrendStore(std::size_t samples = kTrendSamples) : samples_(samples) {}

  // A row of trend `key`; a trend whose series changed (a reload changed the device) starts anew.
  void add(std::string_view key, const std::vector<TrendSeries>& series, std::int64_t unix_ms,
           std::span<const float> values);
  // Drops every trend not named in `keys` (devices and buses a reload removed).
  void keep_only(const std::vector<std::string>& keys);
  [[nodiscard]] const std::map<std::string, Trend, std::less<>>& trends() const { return trends_; }
  [[nodiscard]] std::size_t samples() const { return samples_; }
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  std::size_t samples_;
  std::map<std::string, Trend, std::less<>> trends_;
};

}  // namespace drivegate
