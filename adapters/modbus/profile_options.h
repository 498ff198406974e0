// A profile's device options ([options.NAME]) and the rpm factors made of them (rpm_factor =
// "120 / motor_poles"): read from the profile's TOML, the factor's text parsed once and evaluated
// with a device's values, and a device's [device.options] applied to the profile. Pure.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivegate/options.h"
#include "drivegate/toml_reader.h"
#include "profile.h"

namespace drivegate::modbus_device {

// An option's name: snake_case, 1..32 characters, not one the adapter takes itself (profile,
// attempts, ...: settings.h, kOptionSchema).
bool valid_option_name(std::string_view name, std::string& why);

// Every [options.NAME] table of `root` into profile.options, errors into `diag`; false when one
// was left out for an error.
bool read_profile_options(const toml::table& root, TableReader& top, Diagnostics& diag,
                          Profile& profile);

// `text` ("max_frequency_hz * 120 / motor_poles / 100") as a factor: numbers and option names of
// `options` joined by '*' and '/', left to right; nullopt and `why` when it is empty, names an
// option the profile does not declare, ends in an operator, or can be 0 or divide by 0 within the
// options' ranges.
std::optional<RpmFactor> parse_rpm_factor(std::string_view text,
                                          const std::vector<ProfileOption>& options,
                                          std::string& why);

// The factor with the options' values (1 without terms).
double factor_value(const RpmFactor& factor, const std::vector<ProfileOption>& options);

// The device's values of the profile's options (those `options` carries; the others keep their
// default): false and `error` ("option motor_poles: ...") for a value that is not a number within
// the option's range.
bool apply_options(Profile& profile, const Options& options, std::string& error);

// A number as an option's text: the shortest that reads back the same ("4", "0.01").
std::string number_text(double v);

// The options in effect, as text: "motor_poles = 2, max_frequency_hz = 50 (default)"; empty
// without options.
std::string options_text(const Profile& profile);

}  // namespace drivegate::modbus_device
