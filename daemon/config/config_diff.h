// What a reload changes (Daemon::reload, Gateway::adopt): the devices and buses of the running
// configuration against the new one, by name. A device whose settings are all the same is kept as
// it runs (its driver, command in force, failsafe timer and latch, counters), whatever else
// changes on its line; a bus whose own settings are the same keeps its port open, whatever its
// devices do. Pure: two configurations in, the differences out, each said in words for the log.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"

namespace drivegate {

// Equal but for where in the file they were declared.
bool same_settings(const BusConfig& a, const BusConfig& b);
bool same_settings(const DeviceConfig& a, const DeviceConfig& b);

// What differs, one "key old -> new" each ("baud 9600 -> 19200", "poll_ms 500 -> 250",
// "option monitors [0D00] -> [0D00, 0D01]"); empty when the settings are the same.
std::vector<std::string> changes(const BusConfig& running, const BusConfig& next);
std::vector<std::string> changes(const DeviceConfig& running, const DeviceConfig& next);
// A listener's policy, which a reload applies to it as it runs ("access operate -> read",
// "allow [192.168.1.0/24] -> [any]", "word_order big -> little", "TLS roles", "TLS files").
std::vector<std::string> changes(const modbus::ListenerPolicy& running,
                                 const modbus::ListenerPolicy& next);

struct Changed {
  std::string name;
  std::vector<std::string> what;  // changes()
};

struct ConfigDiff {
  std::vector<std::string> devices_kept, devices_added, devices_removed;
  std::vector<Changed> devices_changed;  // started afresh
  std::vector<std::string> buses_kept, buses_added, buses_removed;
  std::vector<Changed> buses_reopened;
};

ConfigDiff diff_config(const Config& running, const Config& next);

}  // namespace drivegate
