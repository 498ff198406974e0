// The throttle on lines any client can cause: a burst, then one per interval, and the count of
// what was held back in the next line written. On made-up time.
#include "net/log_throttle.h"

#include <gtest/gtest.h>

namespace drivegate::net {
namespace {

using namespace std::chrono_literals;
using Clock = LogThrottle::Clock;

// How many of `n` occurrences, `gap` apart from `at`, are written; `at` is moved past them.
int written(LogThrottle& t, Clock::time_point& at, int n, Clock::duration gap) {
  int w = 0;
  for (int i = 0; i < n; ++i, at += gap) w += t.admit(at).has_value() ? 1 : 0;
  return w;
}

TEST(LogThrottle, ABurstIsWrittenThenOneAnIntervalAndTheHeldAreCounted) {
  LogThrottle t(3, 1s);
  Clock::time_point at{};
  EXPECT_EQ(t.admit(at), 0u);  // the first, nothing held before it
  EXPECT_EQ(t.admit(at), 0u);
  EXPECT_EQ(t.admit(at), 0u);
  for (int i = 0; i < 1000; ++i) EXPECT_FALSE(t.admit(at + 999ms));  // a client in a loop
  EXPECT_EQ(t.admit(at + 1s), 1000u);  // a token back: written, saying how many were not
  EXPECT_FALSE(t.admit(at + 1500ms));
  EXPECT_EQ(t.admit(at + 2s), 1u);
}

TEST(LogThrottle, AFloodWritesAtMostTheBurstPlusOneAnInterval) {
  LogThrottle t(10, 1s);
  Clock::time_point at{};
  // 10,000 occurrences over 10 s: the burst (0..9 ms), then one a second from a second after the
  // bucket was last full (1.009 s .. 9.009 s).
  EXPECT_EQ(written(t, at, 10'000, 1ms), 10 + 9);
}

TEST(LogThrottle, AQuietSpellRefillsTheBurst) {
  LogThrottle t(5, 1s);
  Clock::time_point at{};
  EXPECT_EQ(written(t, at, 5, 0ms), 5);
  EXPECT_FALSE(t.admit(at));
  at += 1h;
  EXPECT_EQ(t.admit(at), 1u);  // the one held back long ago is still reported
  EXPECT_EQ(written(t, at, 10, 0ms), 4);
}

TEST(LogThrottle, OccasionalLinesAreAllWritten) {
  LogThrottle t;
  Clock::time_point at{};
  EXPECT_EQ(written(t, at, 100, 2s), 100);  // a handshake failing now and then: every one
}

TEST(LogThrottle, HeldNoteSaysHowManyOrNothing) {
  EXPECT_EQ(held_note(0), "");
  EXPECT_EQ(held_note(7), " (7 like it not logged)");
}

}  // namespace
}  // namespace drivegate::net
