#include "systemd_notifier.h"

#include <systemd/sd-daemon.h>

#include <string>

namespace drivegate {

SystemdNotifier::SystemdNotifier() {
  std::uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0 && usec > 0) {
    watchdog_period_ = std::chrono::microseconds(usec / 2);
  }
}

void SystemdNotifier::send(std::string_view state) {
  const std::string s(state);
  sd_notify(0, s.c_str());
}

void SystemdNotifier::ready(std::string_view status) {
  send("READY=1\nSTATUS=" + std::string(status));
}
void SystemdNotifier::status(std::string_view status) {
  send("STATUS=" + std::string(status));
}
void SystemdNotifier::reloading() {
  send("RELOADING=1\nSTATUS=reloading configuration");
}
void SystemdNotifier::stopping() {
  send("STOPPING=1\nSTATUS=stopping drives");
}
void SystemdNotifier::watchdog() {
  send("WATCHDOG=1");
}

}  // namespace drivegate
