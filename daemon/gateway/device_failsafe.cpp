// The device's PLC-loss failsafe (docs/safety.md): what it does when the PLC stops writing, and
// how it retries a failsafe write the drive did not take. The timer itself is failsafe.h.
#include "gateway/device.h"

namespace drivegate {

namespace {
// A failed failsafe write is tried again after this, not on every 100 ms tick.
constexpr Millis kFailsafeRetry{1000};
}  // namespace

void Device::failsafe_tick(TimePoint now) {
  if (failsafe_.expired(now)) {
    failsafe_now_ = config_.failsafe.action;
    failsafe_done_ = false;
    failsafe_gave_up_ = false;
    failsafe_retry_at_ = {};
    log_->warn(
        "device {}: no Modbus write to command, setpoint or heartbeat for {} ms: "
        "failsafe {} (latched until a run command is written)",
        config_.name, failsafe_.timeout().count(), to_string(failsafe_now_));
    record_changes();  // the trip before the failsafe's own write, in the history too
  }
  if (failsafe_.latched()) enforce_failsafe(now);
}

// Takes the action, and keeps it taken while latched: a stop is sent again whenever the driver's
// command in force becomes a run once more (a driver that resumes its run after comm_lost).
void Device::enforce_failsafe(TimePoint now) {
  if (failsafe_now_ == FailsafeAction::hold || failsafe_busy_ || failsafe_gave_up_ || comm_lost() ||
      now < failsafe_retry_at_) {
    return;
  }
  const bool runs = is_run(driver_->common().command);
  if (failsafe_now_ == FailsafeAction::preset) {
    if (failsafe_done_) return;
    if (!runs) {
      failsafe_done_ = true;  // a stopped drive is not started by a failsafe
      return;
    }
  } else if (failsafe_done_ && !runs) {
    return;
  }
  failsafe_busy_ = true;
  const FailsafeAction action = failsafe_now_;
  auto done = [this, action](Outcome o) { failsafe_settled(action, o); };
  const Session session = gateway_session(SourceKind::failsafe);
  // The preset speed goes to setpoint_rpm (register 1), a stop to command (register 0).
  const bool preset = action == FailsafeAction::preset;
  const auto value = static_cast<std::uint16_t>(
      preset ? config_.failsafe.preset_rpm
             : static_cast<int>(action == FailsafeAction::quick_stop ? Command::quick_stop
                                                                     : Command::stop));
  const auto address = static_cast<std::uint16_t>(preset ? 1 : 0);
  const std::span<const std::uint16_t> in(&value, 1);
  Answer a = answer_to(session, done, describe_registers(Table::holding, address, in), now);
  const Outcome outcome =
      answered(a, submit(session, Table::holding, address, in, a, now, Origin::gateway), now);
  if (outcome != Outcome::ok) failsafe_settled(action, outcome);
}

void Device::failsafe_settled(FailsafeAction action, Outcome outcome) {
  failsafe_busy_ = false;
  if (!failsafe_.latched()) return;  // a run command reset it meanwhile
  if (outcome == Outcome::ok) {
    if (!failsafe_done_) {
      log_->info("device {}: failsafe {} confirmed by the drive", config_.name, to_string(action));
    }
    failsafe_done_ = true;
    return;
  }
  log_->warn("device {}: failsafe {} not confirmed ({})", config_.name, to_string(action),
             to_string(outcome));
  if (action == FailsafeAction::preset ||
      (action == FailsafeAction::quick_stop && outcome == Outcome::invalid_value)) {
    failsafe_now_ = FailsafeAction::stop;  // next tick: a plain stop instead
    failsafe_done_ = false;
    return;
  }
  if (outcome == Outcome::invalid_value) {
    failsafe_gave_up_ = true;
    log_->error("device {}: refuses {} (invalid value): the failsafe cannot act on it",
                config_.name, to_string(action));
    return;
  }
  failsafe_retry_at_ = last_tick_ + kFailsafeRetry;
}

}  // namespace drivegate
