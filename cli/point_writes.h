// Writing points of one device straight on its serial line, without the Modbus server and with
// maintenance-only points enabled: what `drivegate write` and `drivegate action` share. Each write
// goes through the device's own validated, confirmed path, exactly as a Modbus write would.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"
#include "plugin/plugins.h"

namespace drivegate::cli {

struct Assignment {
  std::string point;
  std::string value;  // a number, or one of the point's labels
};

struct PointWriteJob {
  const Config* config;
  const PluginRegistry* plugins;
  std::string device;
  std::vector<Assignment> writes;  // in order; the first failure ends the job
  Millis timeout{10'000};          // to come online
  // A string point that says why a write failed, printed after its exception (an action's
  // message point); empty: none.
  std::string message_point;
};

// Opens only the device's bus, waits for the device to come online, writes each point in order,
// waiting for the drive to confirm each, and prints one line per write. Returns the exit code.
int run_point_writes(const PointWriteJob& job);

}  // namespace drivegate::cli
