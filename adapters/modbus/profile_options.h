// A profile's device options ([options.NAME]) and the rpm factors and offsets made of them
// (rpm_factor = "120 / motor_poles", rpm_offset = "min_frequency_hz * 120 / motor_poles"): read
// from the profile's TOML, the texts parsed once and evaluated with a device's values, and a
// device's [device.options] applied to the profile. Pure.
#pragma once

#include <cstdint>
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

// Which of speed_rpm's and setpoint_rpm's two expressions: rpm = value x factor + offset.
enum class RpmPart : std::uint8_t { factor, offset };

// `text` ("max_frequency_hz * 120 / motor_poles / 100") as a factor: terms joined by '*' and '/',
// left to right, a term a number, a name of `options`, or the difference of two of them in
// parentheses ("(max_frequency_hz - min_frequency_hz)"). nullopt and `why` when it is empty, names
// an option the profile does not declare, ends in an operator, has anything else in parentheses,
// a term that can be 0 within its option's range or a difference that is always 0, or is not
// above 0 with the options' defaults (a required option's example).
std::optional<RpmFactor> parse_rpm_factor(std::string_view text,
                                          const std::vector<ProfileOption>& options,
                                          std::string& why);
// The same as an offset ("min_frequency_hz * 120 / motor_poles"): it may be 0 or below, but not
// divide by 0.
std::optional<RpmFactor> parse_rpm_offset(std::string_view text,
                                          const std::vector<ProfileOption>& options,
                                          std::string& why);

// The expression with the options' values (1 without terms).
double factor_value(const RpmFactor& factor, const std::vector<ProfileOption>& options);

// What is wrong with the expression's value with the options' values ("is -12 with
// max_frequency_hz = 10, min_frequency_hz = 50: a factor must be above 0"): a factor must be a
// number above 0, an offset a number. Empty when nothing is.
std::string rpm_problem(const RpmFactor& e, RpmPart part,
                        const std::vector<ProfileOption>& options);

// The factor and offset with the options' values (RpmScale, profile.h).
RpmScale rpm_scale(const RpmFactor& factor, const std::optional<RpmFactor>& offset,
                   const std::vector<ProfileOption>& options);

// speed_rpm's and setpoint_rpm's factors above 0 and offsets numbers with the options' values: a
// device's options may make a difference 0 or negative (max_frequency_hz at or below
// min_frequency_hz). false and `error` when not.
bool check_rpm(const Profile& profile, std::string& error);

// What a required option ([options.NAME] with an example, no default) a device does not set
// becomes: a refused device (the driver), or its example (the simulator).
enum class Unset : std::uint8_t { refuse, example };

// A required option's default in a device's option schema (specialise.h): the daemon's schema
// gives every option a default, and this one says "not set" (no drive's parameter is near it).
inline constexpr double kUnsetOption = -1e300;

// The device's values of the profile's options (those `options` carries; the others keep their
// default): false and `error` ("option motor_poles: ...") for a value that is not a number within
// the option's range, a required option not set (with Unset::refuse: the error names it and its
// description), or (check_rpm) options that make a factor 0 or below.
bool apply_options(Profile& profile, const Options& options, std::string& error,
                   Unset unset = Unset::refuse);

// A number as an option's text: the shortest that reads back the same ("4", "0.01").
std::string number_text(double v);

// The options in effect, as text: "motor_poles = 2 (required), max_frequency_hz = 50 (default)";
// empty without options.
std::string options_text(const Profile& profile);

}  // namespace drivegate::modbus_device
