// net::Timer on a clock moved by hand (tests/support/manual_clock.h): due when the clock says so,
// not when real time has passed; cancelled or replaced, its handler hears operation_aborted.
#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <memory>
#include <optional>

#include "manual_clock.h"
#include "net/clock.h"

namespace drivegate::net {
namespace {

using namespace std::chrono_literals;
using Outcome = std::optional<boost::system::error_code>;

struct Rig {
  test::ManualClock clock;  // outlives io (support/server_thread.h)
  boost::asio::io_context io;
  // Runs what is ready, and what real time brings within `real`.
  void run(std::chrono::milliseconds real = 20ms) {
    io.restart();
    io.run_for(real);
  }
};

TEST(Timer, IsDueWhenItsClockGetsThereNotBefore) {
  Rig r;
  Timer t(r.io.get_executor(), r.clock);
  Outcome got;
  t.expires_after(100ms);
  t.async_wait([&got](const boost::system::error_code& ec) { got = ec; });
  r.run();
  EXPECT_FALSE(got);
  r.clock.advance(99ms);
  r.run();
  EXPECT_FALSE(got);
  r.clock.advance(1ms);
  EXPECT_FALSE(got);  // never inside advance()
  r.run();
  ASSERT_TRUE(got);
  EXPECT_FALSE(*got);
}

TEST(Timer, ADeadlineAlreadyPastIsDueAtOnce) {
  Rig r;
  Timer t(r.io.get_executor(), r.clock);
  Outcome got;
  t.expires_at(r.clock.now() - 1s);
  t.async_wait([&got](const boost::system::error_code& ec) { got = ec; });
  r.run();
  ASSERT_TRUE(got);
  EXPECT_FALSE(*got);
}

TEST(Timer, CancelledOrReplacedTheWaitIsAborted) {
  Rig r;
  Timer t(r.io.get_executor(), r.clock);
  Outcome first;
  Outcome second;
  t.expires_after(10ms);
  t.async_wait([&first](const boost::system::error_code& ec) { first = ec; });
  t.expires_after(50ms);  // as asio's timers: a new deadline aborts the wait in progress
  t.async_wait([&second](const boost::system::error_code& ec) { second = ec; });
  r.clock.advance(10ms);
  r.run();
  ASSERT_TRUE(first);
  EXPECT_EQ(*first, boost::asio::error::operation_aborted);
  EXPECT_FALSE(second);
  t.cancel();
  r.clock.advance(1s);
  r.run();
  ASSERT_TRUE(second);
  EXPECT_EQ(*second, boost::asio::error::operation_aborted);
}

TEST(Timer, DestroyedWithAWaitItsHandlerIsAbortedAndNothingDangles) {
  Rig r;
  Outcome got;
  {
    Timer t(r.io.get_executor(), r.clock);
    t.expires_after(10ms);
    t.async_wait([&got](const boost::system::error_code& ec) { got = ec; });
  }
  r.clock.advance(1s);  // the timer is no longer the clock's to wake
  r.run();
  ASSERT_TRUE(got);
  EXPECT_EQ(*got, boost::asio::error::operation_aborted);
}

TEST(Timer, OnTheSteadyClockItWaitsRealTime) {
  boost::asio::io_context io;
  SteadyClock clock;
  Timer t(io.get_executor(), clock);
  const auto start = clock.now();
  Outcome got;
  t.expires_after(30ms);
  t.async_wait([&got](const boost::system::error_code& ec) { got = ec; });
  io.run();
  ASSERT_TRUE(got);
  EXPECT_FALSE(*got);
  EXPECT_GE(clock.now() - start, 30ms);
}

}  // namespace
}  // namespace drivegate::net
