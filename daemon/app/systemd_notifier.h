// The daemon's side of the systemd service protocol: READY=1 once it can serve, STATUS= lines,
// WATCHDOG=1 from the event loop, RELOADING=1 / STOPPING=1. Does nothing outside systemd.
#pragma once

#include <chrono>
#include <string_view>

namespace drivegate {

class SystemdNotifier {
 public:
  SystemdNotifier();
  void ready(std::string_view status);
  void status(std::string_view status);
  void reloading();
  void stopping();
  void watchdog();
  // Half the interval systemd expects pings at (WatchdogSec=), or zero when it expects none.
  [[nodiscard]] std::chrono::microseconds watchdog_period() const { return watchdog_period_; }

 private:
  void send(std::string_view state);
  std::chrono::microseconds watchdog_period_{0};
};

}  // namespace drivegate
