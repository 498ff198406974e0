// How often a line that anyone able to reach a port can cause gets written. A refused connection,
// a failed TLS handshake or a malformed frame is logged with what says why, but a client doing it
// in a loop must not flood the journal: journald drops a service's messages past its rate limit,
// and would drop the ones that matter with the flood. A token bucket per cause: a burst of
// `burst` lines, then one per `interval`; the lines not written are counted, and the next line
// written says how many (the daemon's counters, in /metrics, count every occurrence).
// Pure: the caller says what time it is.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>

namespace drivegate::net {

class LogThrottle {
 public:
  using Clock = std::chrono::steady_clock;

  LogThrottle() : LogThrottle(10) {}
  explicit LogThrottle(unsigned burst, Clock::duration interval = std::chrono::seconds(1))
      : burst_(burst > 0 ? burst : 1),
        interval_(interval > Clock::duration::zero() ? interval : Clock::duration(1)),
        tokens_(burst_) {}

  // One occurrence at `now`. nullopt: not to be written (it is counted); else write it, saying
  // that this many before it were not.
  std::optional<std::uint64_t> admit(Clock::time_point now) {
    refill(now);
    if (tokens_ == 0) {
      ++held_;
      return std::nullopt;
    }
    --tokens_;
    return std::exchange(held_, 0);
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
  std::uint64_t held_ = 0;
};

// What a written line adds about the ones held back before it: "" or " (N like it not logged)".
inline std::string held_note(std::uint64_t held) {
  return held == 0 ? std::string() : " (" + std::to_string(held) + " like it not logged)";
}

}  // namespace drivegate::net
