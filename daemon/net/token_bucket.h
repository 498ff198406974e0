// A token bucket: `burst` tokens, and one more each `interval` until it holds `burst` again. What
// paces the lines anyone able to reach a port can cause (log_throttle.h) and the audit trail's
// records of a flood of writes (history/command_fold.h). Pure: the caller says what time it is.
#pragma once

#include <chrono>
#include <cstdint>

namespace drivegate::net {

class TokenBucket {
 public:
  using Clock = std::chrono::steady_clock;

  explicit TokenBucket(unsigned burst = 10, Clock::duration interval = std::chrono::seconds(1))
      : burst_(burst > 0 ? burst : 1),
        interval_(interval > Clock::duration::zero() ? interval : Clock::duration(1)),
        tokens_(burst_) {}

  // Whether a token is there at `now`.
  [[nodiscard]] bool ready(Clock::time_point now) {
    refill(now);
    return tokens_ > 0;
  }
  // Takes a token at `now`: false if there is none.
  bool take(Clock::time_point now) {
    if (!ready(now)) return false;
    --tokens_;
    return true;
  }
  // Every token spent at `now`: the next one comes an interval later.
  void drain(Clock::time_point now) {
    tokens_ = 0;
    refilled_ = now;
  }
  // Whether it is full at `now`: as if never used.
  [[nodiscard]] bool full(Clock::time_point now) {
    refill(now);
    return tokens_ == burst_;
  }

 private:
  void refill(Clock::time_point now) {
    if (tokens_ == burst_) {
      refilled_ = now;  // a full bucket starts refilling from its first use
      return;
    }
    const auto whole = (now - refilled_) / interval_;
    if (whole <= 0) return;
    if (static_cast<std::uint64_t>(whole) >= burst_ - tokens_) {
      tokens_ = burst_;
      refilled_ = now;
      return;
    }
    tokens_ += static_cast<unsigned>(whole);
    refilled_ += whole * interval_;
  }

  unsigned burst_;
  Clock::duration interval_;
  unsigned tokens_;
  Clock::time_point refilled_{};
};

}  // namespace drivegate::net
