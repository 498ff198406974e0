#include "gateway/failsafe_enforcer.h"

namespace drivegate {

void FailsafeEnforcer::trip(FailsafeAction action) {
  action_ = action;
  state_ = in_flight() ? State::sending : State::due;
  retry_at_ = {};
}

// Takes the action, and keeps it taken while latched: a stop is sent again whenever the driver's
// command in force becomes a run once more (a driver that resumes its run after comm_lost).
std::optional<FailsafeAction> FailsafeEnforcer::send(TimePoint now, bool runs) {
  if (action_ == FailsafeAction::hold || in_flight() || state_ == State::gave_up ||
      now < retry_at_) {
    return std::nullopt;
  }
  if (action_ == FailsafeAction::preset) {
    if (state_ == State::confirmed) return std::nullopt;
    if (!runs) {
      state_ = State::confirmed;  // a stopped drive is not started by a failsafe
      return std::nullopt;
    }
  } else if (state_ == State::confirmed && !runs) {
    return std::nullopt;
  }
  state_ = state_ == State::confirmed ? State::resending : State::sending;
  return action_;
}

FailsafeEnforcer::Settled FailsafeEnforcer::settled(FailsafeAction sent, Outcome outcome,
                                                    bool latched, TimePoint last_tick) {
  const bool was_confirmed = state_ == State::resending;
  state_ = was_confirmed ? State::confirmed : State::due;
  if (!latched) return Settled::unlatched;
  if (outcome == Outcome::ok) {
    state_ = State::confirmed;
    return was_confirmed ? Settled::reconfirmed : Settled::confirmed;
  }
  if (sent == FailsafeAction::preset ||
      (sent == FailsafeAction::quick_stop && outcome == Outcome::invalid_value)) {
    action_ = FailsafeAction::stop;
    state_ = State::due;
    return Settled::fell_back;
  }
  if (outcome == Outcome::invalid_value) {
    state_ = State::gave_up;
    return Settled::gave_up;
  }
  retry_at_ = last_tick + kRetry;
  return Settled::retry;
}

}  // namespace drivegate
