// The servers' time, injected as the bus engine's is (bus/bus_engine.h's BusClock): every
// deadline of a network server (a client idle too long, a frame or a request left unfinished, a
// TLS handshake that drags, an accept back-off, a paced request) is a time point of a Clock, and
// waits on a Timer that follows that clock. The daemon runs them on SteadyClock; the tests on a
// clock they move by hand (tests/support/manual_clock.h), so a 60 s idle timeout is tested in
// no time and the same way on every machine.
#pragma once

#include <boost/asio/any_io_executor.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>

namespace drivegate::net {

using TimePoint = std::chrono::steady_clock::time_point;

class Timer;

class Clock {
 public:
  virtual ~Clock() = default;
  [[nodiscard]] virtual TimePoint now() const = 0;

 protected:
  friend class Timer;
  // The timers waiting on this clock. A clock that moves in jumps (a test's) wakes them when it
  // moves (Timer::time_moved); the steady clock needs no list.
  virtual void attach(Timer& /*timer*/) {}
  virtual void detach(Timer& /*timer*/) {}
};

// The machine's monotonic clock: what the daemon runs on.
class SteadyClock final : public Clock {
 public:
  [[nodiscard]] TimePoint now() const override { return std::chrono::steady_clock::now(); }
};

// One deadline on a Clock, woken by the event loop: like asio::steady_timer (one wait at a time,
// cancel() aborts it), but "due" means the clock's now() has reached the deadline. Cancelled or
// destroyed, the handler is called with operation_aborted, as asio's is.
class Timer {
 public:
  using Handler = std::function<void(const boost::system::error_code&)>;

  Timer(const boost::asio::any_io_executor& executor, Clock& clock);
  ~Timer();
  Timer(const Timer&) = delete;
  Timer& operator=(const Timer&) = delete;

  // Replaces the deadline; a wait in progress is aborted (its handler gets operation_aborted).
  void expires_at(TimePoint at);
  void expires_after(std::chrono::steady_clock::duration d) { expires_at(clock_.now() + d); }
  [[nodiscard]] TimePoint expiry() const { return at_; }
  // Calls `handler` once: with success when the clock reaches the deadline, or aborted.
  void async_wait(Handler handler);
  void cancel();

  // The clock jumped: a wait whose deadline has come is completed (in a later turn of the event
  // loop, never inside this call), one still ahead waits for the rest.
  void time_moved();

 private:
  struct Wait;
  void arm();

  Clock& clock_;
  boost::asio::steady_timer wake_;  // the event loop's alarm: the rest of the wait, in real time
  TimePoint at_{};
  std::shared_ptr<Wait> wait_;  // the wait in progress, if any
};

}  // namespace drivegate::net
