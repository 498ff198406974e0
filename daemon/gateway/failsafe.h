// The PLC-loss watchdog of one device (docs/safety.md): pure timekeeping, no I/O, no logging.
// The Device feeds it on every valid Modbus write to the command, setpoint or heartbeat register,
// asks it each housekeeping tick whether the timeout just expired, and clears the latch on a new
// run command.
//
//   off ------ (timeout 0: never leaves)
//   waiting -- first valid write --> armed -- no write for `timeout` --> latched
//   latched -- run_forward / run_reverse written --> armed (timer restarts at that write)
//
// The timer starts at the first valid write: a gateway no PLC ever wrote to does not trip, so a
// daemon restarted while its PLC is away does not stop drives someone runs by hand.
#pragma once

#include "drivegate/driver.h"

namespace drivegate {

class FailsafeWatchdog {
 public:
  enum class State : std::uint8_t { off, waiting, armed, latched };

  explicit FailsafeWatchdog(Millis timeout)
      : timeout_(timeout), state_(timeout.count() > 0 ? State::waiting : State::off) {}

  // A valid write to command, setpoint or heartbeat. Does not clear the latch.
  void fed(TimePoint now) {
    if (state_ == State::off) return;
    last_ = now;
    if (state_ == State::waiting) state_ = State::armed;
  }
  // True once: at the first call after `timeout` passed without a write. Latches.
  bool expired(TimePoint now) {
    if (state_ != State::armed || now - last_ < timeout_) return false;
    state_ = State::latched;
    return true;
  }
  // A run command was written: true if that cleared the latch.
  bool reset(TimePoint now) {
    if (state_ != State::latched) return false;
    state_ = State::armed;
    last_ = now;
    return true;
  }
  [[nodiscard]] bool latched() const { return state_ == State::latched; }
  [[nodiscard]] State state() const { return state_; }
  [[nodiscard]] Millis timeout() const { return timeout_; }

 private:
  Millis timeout_;
  State state_;
  TimePoint last_{};
};

}  // namespace drivegate
