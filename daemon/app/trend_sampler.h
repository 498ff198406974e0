// The trends' samples (history/trend_store.h), taken by the daemon once a second: each drive's
// speed, setpoint and the adapter points marked PointSpec::trend, as the driver holds them (none
// while comm is lost: a gap, not the last value again); each bus's line utilisation over the
// second past (bytes x character time, status_view.h's line_busy_seconds).
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "gateway/gateway.h"
#include "history/trend_store.h"

namespace drivegate {

inline constexpr Millis kTrendPeriod{1000};

class TrendSampler {
 public:
  explicit TrendSampler(TrendStore& store) : store_(store) {}
  // One row of every trend at `unix_ms` (wall clock) / `now` (the steady clock the rates use);
  // trends of devices and buses no longer in `gateway` are dropped.
  void sample(const Gateway& gateway, std::int64_t unix_ms, TimePoint now);

 private:
  TrendStore& store_;
  struct BusMark {
    double busy_seconds = 0;
    TimePoint at{};
  };
  std::map<std::string, BusMark, std::less<>> buses_;
  std::vector<TrendSeries> series_;  // scratch, kept for its capacity
  std::vector<float> values_;
};

}  // namespace drivegate
