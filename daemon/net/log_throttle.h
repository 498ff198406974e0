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

#include "net/token_bucket.h"

namespace drivegate::net {

class LogThrottle {
 public:
  using Clock = TokenBucket::Clock;

  LogThrottle() : LogThrottle(10) {}
  explicit LogThrottle(unsigned burst, Clock::duration interval = std::chrono::seconds(1))
      : bucket_(burst, interval) {}

  // One occurrence at `now`. nullopt: not to be written (it is counted); else write it, saying
  // that this many before it were not.
  std::optional<std::uint64_t> admit(Clock::time_point now) {
    if (!bucket_.take(now)) {
      ++held_;
      return std::nullopt;
    }
    return std::exchange(held_, 0);
  }

 private:
  TokenBucket bucket_;
  std::uint64_t held_ = 0;
};

// What a written line adds about the ones held back before it: "" or " (N like it not logged)".
inline std::string held_note(std::uint64_t held) {
  return held == 0 ? std::string() : " (" + std::to_string(held) + " like it not logged)";
}

}  // namespace drivegate::net
