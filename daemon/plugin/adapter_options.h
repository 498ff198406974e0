// Adapter options given as text (command lines, the schema's defaults), checked against the
// adapter's schema. The TOML form, `[device.options]`, is read by config_loader.cpp with the same
// checks.
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "drivegate/adapter.h"

namespace drivegate {

// One adapter option from text, checked against its spec; nullopt and `error` when it fails.
// Numbers are decimal, as in TOML: "010" is ten, and "0x10", "+1", " 1", "inf" are refused.
std::optional<OptionValue> parse_option_text(const OptionSpec& spec, std::string_view text,
                                             std::string& error);
// Why the adapter's option schema is unusable ("option 'count': default '12' is invalid: must be
// in 1..10 (got 12)"), or empty when it is fine: every option has a non-empty name of its own, a
// description and a default that its own spec accepts. The plugin loader refuses an adapter
// failing this, so the rest of drivegate can rely on the defaults.
std::string check_option_schema(const AdapterDescriptor& adapter);
// Every option of an adapter at its default. Throws std::logic_error for a default that does not
// parse: check_option_schema() keeps such an adapter from being loaded at all.
Options default_options(const AdapterDescriptor& adapter);

// Sets option `name` of `options` from text, checked against the adapter's schema (`drivegate sim
// --set NAME=VALUE`, an adapter's demo options); false and `error` ("NAME: why") when the adapter
// has no such option or the text is not a valid value.
bool set_option_text(const AdapterDescriptor& adapter, Options& options, std::string_view name,
                     std::string_view text, std::string& error);
// `value` as a TOML value: 12, 0.5, true, "text" (escaped), ["a", "b"].
std::string toml_literal(const OptionValue& value);

// Whether `value` is one of `choices` ("normal|continuous"); empty choices allow anything.
bool in_choices(std::string_view choices, std::string_view value);
// "MIN..MAX" of a bounded option, for messages.
std::string range_text(const OptionSpec& spec);

}  // namespace drivegate
