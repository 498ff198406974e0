// The daemon's logger. In a terminal: timestamped lines on stderr. Under systemd (JOURNAL_STREAM
// names our stderr): entries sent to the journal directly, with the message's priority and,
// when the message concerns a device or a bus, the fields DEVICE=, BUS= and UNIT= (the Modbus
// unit id), so `journalctl -u drivegate DEVICE=washer-1` selects one drive. A message concerns a
// device or a bus by its prefix: every one is "device NAME: ..." or "bus NAME: ..." (bus.cpp,
// device.cpp, gateway.cpp); describe_devices() tells the journal which bus and unit each
// device has.
#pragma once

#include <spdlog/logger.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config/config.h"

namespace drivegate {

std::shared_ptr<spdlog::logger> make_logger(std::string_view name, spdlog::level::level_enum level);
std::optional<spdlog::level::level_enum> parse_log_level(std::string_view s);

// A configured device's place, for the journal fields of messages about it.
struct DeviceTag {
  std::string name;
  std::string bus;
  std::uint8_t unit_id = 0;
};

// What one message is about: empty strings / nullopt where it does not say.
struct LogSubject {
  std::string device;
  std::string bus;
  std::optional<std::uint8_t> unit;
};

// "device D: ..." names D; "bus B: ..." names B, and "bus B: device D ..." both. The tags then
// fill in the bus and unit of a named device (a device name the tags lack keeps no unit).
LogSubject log_subject(std::string_view message, const std::vector<DeviceTag>& devices);

// The syslog priority (sd-daemon(3), syslog(3)) a message of `level` is logged with.
int syslog_priority(spdlog::level::level_enum level);

// Gives the logger's journal sink, if it has one, the devices of the configuration in force;
// call again after a reload. Without a journal sink it does nothing.
void describe_devices(spdlog::logger& log, std::vector<DeviceTag> devices);
// The same, with every [[device]] of `config`.
void describe_devices(spdlog::logger& log, const Config& config);

}  // namespace drivegate
