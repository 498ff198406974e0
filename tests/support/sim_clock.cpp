#include "sim_clock.h"

#include <stdexcept>
#include <string>

namespace drivegate::test {

namespace {
// More steps than this at one instant is an engine that rearms its alarm for "now" forever.
constexpr std::uint64_t kMaxStepsAtOneInstant = 100'000;
}  // namespace

bool SimClock::step(TimePoint until) {
  const TimePoint next_event = events_.empty() ? TimePoint::max() : events_.begin()->first.first;
  const TimePoint next_alarm = alarm_.value_or(TimePoint::max());
  const TimePoint next = std::min(next_event, next_alarm);
  if (next > until || next == TimePoint::max()) return false;
  now_ = std::max(now_, next);
  if (now_ == spin_at_) {
    if (++spins_ > kMaxStepsAtOneInstant) {
      throw std::runtime_error("simulated time stands still at " +
                               std::to_string(now_.time_since_epoch().count()) +
                               " ns: something rearms for now forever");
    }
  } else {
    spin_at_ = now_;
    spins_ = 0;
  }
  if (next_event <= next_alarm) {
    auto node = events_.extract(events_.begin());
    node.mapped()();
  } else {
    alarm_.reset();
    if (alarm_handler_) alarm_handler_();
  }
  return true;
}

}  // namespace drivegate::test
