// [mqtt]: the Sparkplug B northbound's broker, identity, report-by-exception limits and command
// policy (docs/mqtt.md). Used by config_loader.cpp only.
#pragma once

#include <toml++/toml.h>

#include "config.h"
#include "drivegate/toml_reader.h"

namespace drivegate {

// After the devices are read: their names become Sparkplug device ids, which must be valid ones.
void read_mqtt(const toml::table& root, Config& cfg, Diagnostics& diag);

}  // namespace drivegate
