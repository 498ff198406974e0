// The device's options: the schema the gateway validates them against, the profile they name
// (found and read here, the one place the adapter touches a file), and the values the driver and
// the simulator use.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "drivegate/driver.h"
#include "drivegate/options.h"
#include "profile.h"

namespace drivegate::modbus_device {

inline constexpr std::array<OptionSpec, 3> kOptionSchema = {{
    {"profile", OptionType::string, "example-vfd",
     "the device's profile: a name (found in /etc/drivegate/profiles, then "
     "/usr/share/drivegate/profiles, then the profiles shipped in the plugin) or a file's path"},
    {"attempts", OptionType::integer, "3", "sends of a request before giving up on it", 1, 10},
    {"comm_timeout_ms", OptionType::integer, "3000", "no good reply for this long: comm_lost", 500,
     600000},
}};

// Where a profile named by name is looked for, in this order, before the shipped copies.
inline constexpr std::array<const char*, 2> kProfileDirs = {"/etc/drivegate/profiles",
                                                            "/usr/share/drivegate/profiles"};
// A profile file larger than this is refused (a profile of 2000 points is about 100 KiB).
inline constexpr std::size_t kMaxProfileBytes = 1 << 20;

struct Settings {
  Profile profile;
  std::string profile_source;  // the file it was read from, or "shipped example-vfd"
  std::uint8_t attempts = 3;
  Millis comm_timeout{3000};
};

// The options as the driver and simulator use them, the profile read and validated: nullopt with
// `error` naming the option (and the profile's file and line) when they do not make a device.
std::optional<Settings> parse_settings(const Options& options, std::string& error);

// The profile called `name` (or at the path `name`): its text and where it came from, or nullopt
// with `error`.
struct ProfileText {
  std::string text;
  std::string source;
};
std::optional<ProfileText> find_profile(const std::string& name, std::string& error);

// The slave's address, 1..247 (Serial Line 2.2; the broadcast 0 is never polled).
std::optional<std::uint8_t> device_address(std::uint32_t address, std::string& error);

}  // namespace drivegate::modbus_device
