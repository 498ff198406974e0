// Time for the network servers' tests (net/clock.h): a clock that stands still until the test
// moves it, and then wakes every timer waiting on it. Call everything on the servers' event-loop
// thread (the harnesses' on_io), as the servers themselves are.
#pragma once

#include <chrono>
#include <unordered_set>
#include <vector>

#include "net/clock.h"

namespace drivegate::test {

class ManualClock final : public net::Clock {
 public:
  explicit ManualClock(net::TimePoint start = net::TimePoint{} + std::chrono::hours(1))
      : now_(start) {}

  [[nodiscard]] net::TimePoint now() const override { return now_; }
  // Moves time on by `d`: the timers whose deadlines that reaches complete (in a later turn of
  // the event loop), the others wait for the rest.
  void advance(std::chrono::steady_clock::duration d) {
    now_ += d;
    const std::vector<net::Timer*> waiting(timers_.begin(), timers_.end());
    for (net::Timer* t : waiting) {
      if (timers_.count(t) != 0) t->time_moved();
    }
  }

 protected:
  void attach(net::Timer& timer) override { timers_.insert(&timer); }
  void detach(net::Timer& timer) override { timers_.erase(&timer); }

 private:
  net::TimePoint now_;
  std::unordered_set<net::Timer*> timers_;
};

}  // namespace drivegate::test
