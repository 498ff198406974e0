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
//
// A reload that changes the device carries the watchdog over to the new device (carry_over):
// armed with the deadline the PLC's last write set, or latched. A reload never moves a deadline
// already running; the new configuration's timeout (0: off) counts from the PLC's next write.
#pragma once

#include "drivegate/driver.h"

namespace drivegate {

class FailsafeWatchdog {
 public:
  enum class State : std::uint8_t { off, waiting, armed, latched };

  explicit FailsafeWatchdog(Millis timeout)
      : configured_(timeout),
        timeout_(timeout),
        state_(timeout.count() > 0 ? State::waiting : State::off) {}

  // This watchdog is a new device's, `old` the one of the device a reload replaced: an armed or
  // latched `old` goes on here, its deadline (last write + its timeout) unchanged; otherwise this
  // one starts as configured (waiting, or off).
  void carry_over(const FailsafeWatchdog& old) {
    if (old.state_ != State::armed && old.state_ != State::latched) return;
    state_ = old.state_;
    last_ = old.last_;
    timeout_ = old.timeout_;
  }
  // A valid write to command, setpoint or heartbeat. Does not clear the latch. From here on the
  // configured timeout is the one in force; a configured 0 turns the watchdog off.
  void fed(TimePoint now) {
    timeout_ = configured_;
    if (state_ == State::off) return;
    last_ = now;
    if (state_ == State::waiting) state_ = State::armed;
    if (state_ == State::armed && configured_.count() == 0) state_ = State::off;
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
    timeout_ = configured_;
    state_ = configured_.count() > 0 ? State::armed : State::off;
    last_ = now;
    return true;
  }
  [[nodiscard]] bool latched() const { return state_ == State::latched; }
  [[nodiscard]] State state() const { return state_; }
  // The timeout of the deadline in force (a replaced device's until the PLC's next write).
  [[nodiscard]] Millis timeout() const { return timeout_; }

 private:
  Millis configured_;  // the device's failsafe_timeout_ms
  Millis timeout_;
  State state_;
  TimePoint last_{};
};

}  // namespace drivegate
