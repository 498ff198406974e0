// The device's options: the schema the gateway validates them against, the profile they name
// (found and read here, the one place the adapter touches a file), and the values the driver and
// the simulator use.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivegate/driver.h"
#include "drivegate/options.h"
#include "profile.h"
#include "profile_options.h"

namespace drivegate::modbus_device {

// The profile a device gets when its options name none.
inline constexpr const char* kDefaultProfile = "example-vfd";

inline constexpr std::array<OptionSpec, 6> kOptionSchema = {{
    {"profile", OptionType::string, kDefaultProfile,
     "the device's profile: a name (found in /etc/drivegate/profiles, then "
     "/usr/share/drivegate/profiles, then the profiles shipped in the plugin) or a file's path"},
    {"attempts", OptionType::integer, "3",
     "sends of a request before giving up on it (a forwarded request is sent once)", 1, 10},
    {"comm_timeout_ms", OptionType::integer, "3000", "no good reply for this long: comm_lost", 500,
     600000},
    {"passthrough", OptionType::boolean, "false",
     "no profile: every Modbus request for the device's unit id is forwarded to the slave as it "
     "is, and its reply is the answer (docs/profiles.md, \"Pass-through\")"},
    {"framing", OptionType::string, "rtu",
     "with passthrough: the slave's framing (a profile's [line] says it otherwise)", 0, 0,
     "rtu|ascii"},
    {"timeout_ms", OptionType::integer, "100",
     "with passthrough: how long the slave may take to start its reply (a profile's [modbus] "
     "says it otherwise)",
     10, 10000},
}};

// Where a profile named by name is looked for, in this order, before the shipped copies.
inline constexpr std::array<const char*, 2> kProfileDirs = {"/etc/drivegate/profiles",
                                                            "/usr/share/drivegate/profiles"};
// A profile file larger than this is refused (a profile of 2000 points is about 100 KiB).
inline constexpr std::size_t kMaxProfileBytes = 1 << 20;

struct Settings {
  Profile profile;
  std::string profile_source;  // the file it was read from, or "shipped example-vfd"
  // The profile as Driver::files_read says it: "profile SOURCE (content FINGERPRINT)".
  std::string files_read;
  std::uint8_t attempts = 3;
  Millis comm_timeout{3000};
};

// The options as the driver and simulator use them, the profile read and validated: nullopt with
// `error` naming the option (and the profile's file and line) when they do not make a device.
// `unset`: what a required option the options leave out becomes (profile_options.h).
std::optional<Settings> parse_settings(const Options& options, std::string& error,
                                       Unset unset = Unset::refuse);

// Whether the bus runs the line the profile's [line] says (baud, parity, stop bits; RTU's 8 data
// bits, Serial Line 2.5.1): false with `error` saying both, so that a device on the wrong line is
// a configuration error rather than a slave that never answers.
bool line_agrees(const Profile& profile, const std::string& source, const LineDefaults& bus,
                 std::string& error);

// A pass-through device's options (passthrough = true): no profile, the line as they say.
struct PassthroughSettings {
  Framing framing = Framing::rtu;
  Millis reply_timeout{100};
  std::uint8_t attempts = 3;  // for the presence probe; a forwarded request goes once
  Millis comm_timeout{3000};
};
// nullopt with `error` when passthrough is false or a profile is named beside it.
std::optional<PassthroughSettings> parse_passthrough(const Options& options, std::string& error);

// The profile called `name` (or at the path `name`): its text and where it came from, or nullopt
// with `error`.
struct ProfileText {
  std::string text;
  std::string source;
};
std::optional<ProfileText> find_profile(const std::string& name, std::string& error);
// What a reload compares of a profile (Driver::files_read): where it came from and a
// fingerprint of its text (FNV-1a, 64 bits, in hex), so that an edit is a changed device.
std::string profile_read(const ProfileText& profile);
// The names of the profiles built into the plugin (`drivegate scan` looks through every profile
// findable by name: these and the files in kProfileDirs).
std::vector<std::string_view> shipped_profile_names();

// The slave's address, 1..247 (Serial Line 2.2; the broadcast 0 is never polled).
std::optional<std::uint8_t> device_address(std::uint32_t address, std::string& error);

}  // namespace drivegate::modbus_device
