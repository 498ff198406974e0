// What a reload does to a device it does not keep as it runs (docs/safety.md, section 2): the
// new one takes over what was promised to the PLC there, the failsafe watchdog above all.
#include "gateway/device.h"

namespace drivegate {

void Device::take_over(const Device& old) {
  heartbeat_ = old.heartbeat_;
  image_.stale();
  // Owed to the drive at that address on that bus: another drive is owed nothing.
  const bool same_drive = old.config_.adapter == config_.adapter &&
                          old.config_.bus == config_.bus && old.config_.address == config_.address;
  const Owed owed = same_drive ? old.driver_->owed() : Owed{};
  driver_->take_over(owed);
  if (driver_->owed().stop_after_trip) {
    log_->warn("device {}: the stop owed to the drive after its trip is carried over the reload",
               config_.name);
  }
  if (const auto held = driver_->owed().setpoint_held_rpm) {
    log_->info(
        "device {}: the setpoint held for the drive's next run ({} rpm) is carried over the "
        "reload",
        config_.name, *held);
  } else if (owed.setpoint_held_rpm) {
    log_->warn(
        "device {}: the setpoint held for the drive's next run ({} rpm) is not carried over "
        "the reload: the new profile cannot write it",
        config_.name, *owed.setpoint_held_rpm);
  }
  failsafe_.carry_over(old.failsafe_);
  if (failsafe_.state() == FailsafeWatchdog::State::armed) {
    log_->info("device {}: the failsafe stays armed across the reload, its deadline unchanged",
               config_.name);
    return;
  }
  if (!failsafe_.latched()) return;
  // Latched there: this driver has not been told. The action (this configuration's) is sent to it
  // at its first tick; the history has the trip already.
  enforcer_.trip(config_.failsafe.action);
  recorder_.latched_before();
  log_->warn("device {}: the failsafe stays latched across the reload: {} sent again", config_.name,
             to_string(enforcer_.action()));
}

}  // namespace drivegate
