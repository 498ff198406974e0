// Simulated time for the bus engine (bus/bus_engine.h): a clock that moves only when the test
// runs it, events fired in time order, and the engine's alarm. Deterministic: no thread, no sleep,
// so the same test gives the same frames at the same simulated microsecond on every machine.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <utility>

#include "bus/bus_engine.h"

namespace drivegate::test {

class SimClock final : public BusClock {
 public:
  explicit SimClock(TimePoint start = TimePoint{} + std::chrono::hours(1)) : now_(start) {}

  [[nodiscard]] TimePoint now() const override { return now_; }
  void set_alarm(TimePoint at) override { alarm_ = at; }
  // Who the alarm calls (the engine's on_alarm).
  void on_alarm(std::function<void()> handler) { alarm_handler_ = std::move(handler); }

  // Calls `f` at `at` (at once if past), after everything already due at that time.
  void at(TimePoint at, std::function<void()> f) {
    events_.emplace(std::make_pair(std::max(at, now_), seq_++), std::move(f));
  }

  // Fires everything due up to `until` in time order (events before the alarm at equal times),
  // then stands at `until`.
  void run_until(TimePoint until) {
    while (step(until)) {
    }
    now_ = std::max(now_, until);
  }
  void run_for(Millis span) { run_until(now_ + span); }
  // Runs until `done()` holds (checked after every event) or `limit` passes; returns done().
  bool run_until(const std::function<bool()>& done, Millis limit) {
    const TimePoint end = now_ + limit;
    while (!done()) {
      if (!step(end)) {
        now_ = std::max(now_, end);
        return done();
      }
    }
    return true;
  }

 private:
  // Fires the earliest thing due by `until`; false when there is none.
  bool step(TimePoint until);

  TimePoint now_;
  std::optional<TimePoint> alarm_;
  std::function<void()> alarm_handler_;
  std::map<std::pair<TimePoint, std::uint64_t>, std::function<void()>> events_;
  std::uint64_t seq_ = 0;
  TimePoint spin_at_{};
  std::uint64_t spins_ = 0;  // steps at one instant: an engine that never lets time pass
};

}  // namespace drivegate::test
