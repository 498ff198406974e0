// The device's PLC-loss failsafe (docs/safety.md): what it does when the PLC stops writing. The
// timer is failsafe.h, the decisions (which action, when to write it again) failsafe_enforcer.h.
#include <optional>

#include "gateway/device.h"

namespace drivegate {

void Device::failsafe_tick(TimePoint now) {
  if (failsafe_.expired(now)) {
    enforcer_.trip(config_.failsafe.action);
    log_->warn(
        "device {}: no Modbus write to command, setpoint or heartbeat for {} ms: "
        "failsafe {} (latched until a run command is written)",
        config_.name, failsafe_.timeout().count(), to_string(enforcer_.action()));
    record_changes();  // the trip before the failsafe's own write, in the history too
  }
  if (failsafe_.latched()) enforce_failsafe(now);
}

// Writes the action when the enforcer says it is due (failsafe_enforcer.h).
void Device::enforce_failsafe(TimePoint now) {
  if (comm_lost()) return;
  const std::optional<FailsafeAction> due = enforcer_.send(now, is_run(driver_->common().command));
  if (!due) return;
  const FailsafeAction action = *due;
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
  using Settled = FailsafeEnforcer::Settled;
  const Settled what = enforcer_.settled(action, outcome, failsafe_.latched(), last_tick_);
  switch (what) {
    case Settled::unlatched:
    case Settled::reconfirmed:
      return;
    case Settled::confirmed:
      log_->info("device {}: failsafe {} confirmed by the drive", config_.name, to_string(action));
      return;
    case Settled::fell_back:
    case Settled::gave_up:
    case Settled::retry:
      break;
  }
  log_->warn("device {}: failsafe {} not confirmed ({})", config_.name, to_string(action),
             to_string(outcome));
  if (what == Settled::gave_up) {
    log_->error("device {}: refuses {} (invalid value): the failsafe cannot act on it",
                config_.name, to_string(action));
  }
}

}  // namespace drivegate
