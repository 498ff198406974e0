#include "net/clock.h"

#include <boost/asio/error.hpp>
#include <boost/asio/post.hpp>
#include <memory>
#include <utility>

namespace drivegate::net {

// What one async_wait left behind, shared with the event loop's completion of wake_: the timer
// may be gone when that runs, and `done` tells it so without touching the timer.
struct Timer::Wait {
  Handler handler;
  std::uint64_t armed = 0;  // which arming of wake_ is current; older completions are stale
  bool done = false;
};

Timer::Timer(const boost::asio::any_io_executor& executor, Clock& clock)
    : clock_(clock), wake_(executor) {
  clock_.attach(*this);
}

Timer::~Timer() {
  // Asio reports a failed cancel() by throwing; a destructor has no one to tell, and the clock
  // must forget this timer whatever happened.
  try {
    cancel();
  } catch (...) {  // nothing to do but to go on
  }
  clock_.detach(*this);
}

void Timer::expires_at(TimePoint at) {
  cancel();  // as asio's timers: a new deadline aborts the wait in progress
  at_ = at;
}

void Timer::async_wait(Handler handler) {
  cancel();
  wait_ = std::make_shared<Wait>();
  wait_->handler = std::move(handler);
  arm();
}

void Timer::cancel() {
  if (!wait_) return;
  const std::shared_ptr<Wait> wait = std::exchange(wait_, nullptr);
  wait->done = true;
  wake_.cancel();
  boost::asio::post(wake_.get_executor(), [handler = std::move(wait->handler)] {
    handler(boost::asio::error::operation_aborted);
  });
}

void Timer::time_moved() {
  if (wait_) arm();
}

// wake_ is set for the rest of the wait as the clock counts it; when it fires, the clock is asked
// again (a clock moved by hand may not have got there yet: then it waits for the rest once more).
void Timer::arm() {
  const auto rest = at_ - clock_.now();
  const std::uint64_t armed = ++wait_->armed;
  wake_.expires_after(rest > rest.zero() ? rest : rest.zero());
  wake_.async_wait([this, wait = wait_, armed](const boost::system::error_code& ec) {
    if (wait->done || armed != wait->armed) return;  // cancelled (the timer may be gone), re-armed
    if (ec) return;  // wake_ itself failed: only cancel() does that, and it set `done`
    if (clock_.now() < at_) {
      arm();
      return;
    }
    wait->done = true;
    wait_.reset();
    Handler handler = std::move(wait->handler);
    handler({});
  });
}

}  // namespace drivegate::net
