// The device's options: the schema the gateway validates them against, and the values the driver
// and the simulator use.
#pragma once

#include <array>
#include <chrono>
#include <optional>
#include <string>
#include <string_view>

#include "codec.h"
#include "drivegate/options.h"

namespace drivegate::fdc1 {

inline constexpr std::array<OptionSpec, 6> kOptionSchema = {{
    // Specs README: slave mode is mode & 3 == 2 (INPUT, mode byte "2: external thermostat =
    // SLAVE MODE"); only then does the speed frame start and stop the motor.
    {"slave_mode", OptionType::boolean, "false",
     "controller programmed in slave mode (mode & 3 == 2): run/stop/setpoint over the line"},
    // Under the 60 s slave-mode watchdog (INPUT, Programming speed): see the static_assert below.
    {"refresh_s", OptionType::integer, "30",
     "slave mode: resend the speed this often (the controller stops after 60 s without)", 1, 59},
    // At least one stream period (0.5 s), so that one status frame can confirm a write.
    {"confirm_ms", OptionType::integer, "5000",
     "a speed write fails (0x0B) when the stream has not shown it within this time", 500, 60000},
    // Two stream periods at least: one lost frame is not a lost link.
    {"stale_ms", OptionType::integer, "2000",
     "comm_lost after this long without a good streamed frame", 1000, 60000},
    {"tolerance_rpm", OptionType::integer, "100",
     "a speed change is confirmed when the streamed speed is this close to the setpoint", 0, 2000},
    {"allow_nv_programming", OptionType::boolean, "false",
     "expose the 22-byte programming (non-volatile memory) as holding points outside maintenance"},
}};

// The schema's spec of option `name` (a compile-time lookup, for the checks below).
constexpr const OptionSpec& option_spec(std::string_view name) {
  for (const OptionSpec& o : kOptionSchema) {
    if (name == o.name) return o;
  }
  throw "no such option";  // not a constant expression: a typo fails the build
}
static_assert(option_spec("refresh_s").max < kSlaveWatchdog.count(),
              "the refresh must come inside the controller's slave-mode watchdog");
static_assert(option_spec("confirm_ms").min >= kStreamPeriod.count());
static_assert(option_spec("stale_ms").min >= 2 * kStreamPeriod.count());

struct Settings {
  bool slave_mode = false;
  std::chrono::seconds refresh{30};
  std::chrono::milliseconds confirm{5000};
  std::chrono::milliseconds stale{2000};
  int tolerance_rpm = 100;
  bool allow_nv_programming = false;
};

// The options as the driver and the simulator use them. The schema has checked every value, and
// no two of these options contradict each other, so this never fails today; `error` would name
// the option if a later one could.
std::optional<Settings> parse_settings(const Options& options, std::string& error);

}  // namespace drivegate::fdc1
