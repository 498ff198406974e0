// The adapter's device options: the schema the gateway validates against, and the values a
// driver or simulator reads from it.
#pragma once

#include <array>
#include <chrono>

#include "drivegate/options.h"

namespace drivegate::fdc1 {

// Ranges: refresh_s must stay under the controller's 60 s slave-mode watchdog (INPUT, Programming
// speed, "the motor will stop if no speed is received within 60s"); stale_ms must exceed the
// 0.5 s stream period (OUTPUT, "Every 0'5 s").
inline constexpr std::array<OptionSpec, 6> kOptionSchema = {{
    {"slave_mode", OptionType::boolean, "false",
     "controller programmed in slave mode (mode & 3 == 2): run/stop/setpoint over the line", 0, 0,
     ""},
    {"refresh_s", OptionType::integer, "30",
     "slave mode: resend the speed this often (the controller stops after 60 s without)", 1, 59,
     ""},
    {"confirm_ms", OptionType::integer, "5000",
     "a speed write fails (0x0B) when the stream has not shown it within this time", 500, 60000,
     ""},
    {"stale_ms", OptionType::integer, "2000",
     "comm_lost after this long without a good streamed frame", 1000, 60000, ""},
    {"tolerance_rpm", OptionType::integer, "100",
     "a speed change is confirmed when the streamed speed is this close to the setpoint", 0, 2000,
     ""},
    {"allow_nv_programming", OptionType::boolean, "false",
     "expose the 22-byte programming (non-volatile memory) as holding points outside maintenance",
     0, 0, ""},
}};

struct Settings {
  bool slave_mode = false;
  std::chrono::seconds refresh{30};
  std::chrono::milliseconds confirm{5000};
  std::chrono::milliseconds stale{2000};
  int tolerance_rpm = 100;
  bool allow_nv_programming = false;
};

// Reads the options, taking the schema's default for any the map lacks.
Settings read_settings(const Options& options);

}  // namespace drivegate::fdc1
