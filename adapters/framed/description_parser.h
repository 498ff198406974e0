// Reading a protocol description (docs/protocols.md): parse_description() takes the TOML text and
// validates it whole, every error "SOURCE:LINE: key: what is wrong" as the daemon's own
// configuration errors read (drivegate/toml_reader.h), all of them in one pass. Pure: the caller
// reads the file (settings.h finds it).
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "description.h"

namespace drivegate::framed {

// A description's name, found as a file name: 1..64 characters of a-z, 0-9, '-' and '_'.
bool valid_protocol_name(std::string_view name);

// The description in `text`, or every error found in it, in file order. `source` names the file.
// The description is returned behind a pointer: its option specs and expressions point into it,
// so it never moves.
std::variant<std::shared_ptr<const Description>, std::vector<std::string>> parse_description(
    std::string_view text, const std::string& source);

}  // namespace drivegate::framed
