// What a device does about a latched PLC-loss failsafe (docs/safety.md): which action is in
// force, whether its write is in flight or was confirmed, and when a failed one is tried again.
// Pure decisions, no driver, no logging: the Device asks it on each tick while the watchdog
// (failsafe.h) is latched whether to write, sends the write, and hands it the outcome.
//
//   due ------- send() --------------------------------------------> sending
//   sending --- settled: ok -------------------------------------> confirmed
//   sending --- settled: preset, or quick_stop invalid -> (action = stop) due
//   sending --- settled: the stop invalid ------------------------> gave_up
//   sending --- settled: other failure ------> due, retried kRetry after the last tick
//   confirmed - send(), a stop whose drive runs again -----------> resending
//   resending - settled: ok ------------------------------------> confirmed
//   resending - settled: failure as sending, but a retry -------> confirmed, retried later
//   due ------- send(), preset while the drive is stopped -------> confirmed (never started)
//   any ------- trip() ---------------------> due (sending if a write is still in flight)
//
// hold never writes; gave_up writes nothing until the next trip. An outcome that arrives while
// the failsafe is not latched (a run command reset it meanwhile) only ends the flight.
#pragma once

#include <cstdint>
#include <optional>

#include "config/config.h"
#include "drivegate/driver.h"
#include "gateway/outcome.h"

namespace drivegate {

class FailsafeEnforcer {
 public:
  enum class State : std::uint8_t { due, sending, confirmed, resending, gave_up };
  // What an outcome did, for the log.
  enum class Settled : std::uint8_t {
    unlatched,    // the failsafe was reset meanwhile: nothing more
    confirmed,    // the drive took the action, for the first time since the trip
    reconfirmed,  // ... once more
    fell_back,    // refused: a plain stop is sent instead
    gave_up,      // the drive cannot take a stop at all (invalid_value)
    retry,        // failed: tried again later
  };
  // A failed failsafe write is tried again after this, not on every 100 ms tick.
  static constexpr Millis kRetry{1000};

  // The watchdog latched (or a reload carried a latched one over): `action` is in force.
  void trip(FailsafeAction action);
  // On a tick while latched and the drive answers: the action to write now, if any (`runs`: the
  // driver's command in force is a run).
  std::optional<FailsafeAction> send(TimePoint now, bool runs);
  // The outcome of the write of `sent`; `latched`: the watchdog still is. A retry is due
  // kRetry after `last_tick`.
  Settled settled(FailsafeAction sent, Outcome outcome, bool latched, TimePoint last_tick);

  [[nodiscard]] FailsafeAction action() const { return action_; }
  [[nodiscard]] State state() const { return state_; }

 private:
  [[nodiscard]] bool in_flight() const {
    return state_ == State::sending || state_ == State::resending;
  }

  // The action in force since the trip: the configured one, or stop when the drive refused
  // quick_stop or the preset speed.
  FailsafeAction action_ = FailsafeAction::stop;
  State state_ = State::due;
  TimePoint retry_at_{};
};

}  // namespace drivegate
