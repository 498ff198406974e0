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
std::optional<OptionValue> parse_option_text(const OptionSpec& spec, std::string_view text,
                                             std::string& error);
// Every option of an adapter at its default.
Options default_options(const AdapterDescriptor& adapter);

// Whether `value` is one of `choices` ("normal|continuous"); empty choices allow anything.
bool in_choices(std::string_view choices, std::string_view value);
// "MIN..MAX" of a bounded option, for messages.
std::string range_text(const OptionSpec& spec);

}  // namespace drivegate
