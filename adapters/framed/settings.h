// The framed adapter's options and where its descriptions come from. The adapter's own schema
// has one option, `protocol`: a description's name (found in /etc/drivegate/protocols, then
// /usr/share/drivegate/protocols, then the copies built into the plugin) or a file's path. Each
// description declares the rest of its device's options, its line and its addresses; the
// descriptor specialised for it (specialise.h) carries them to the core.
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "description.h"
#include "drivegate/options.h"

namespace drivegate::framed {

inline constexpr std::array<OptionSpec, 1> kOptionSchema = {{
    {"protocol", OptionType::string, "",
     "the device's protocol description: a name (found in /etc/drivegate/protocols, then "
     "/usr/share/drivegate/protocols, then the descriptions shipped in the plugin) or a file's "
     "path (docs/protocols.md)"},
}};

// Where a description named by name is looked for, in this order, before the shipped copies.
inline constexpr std::array<const char*, 2> kProtocolDirs = {"/etc/drivegate/protocols",
                                                             "/usr/share/drivegate/protocols"};
// A description file larger than this is refused.
inline constexpr std::size_t kMaxDescriptionBytes = 1 << 20;

// A description's text and the name its errors give it.
struct DescriptionText {
  std::string text;
  std::string source;  // the file's path, or "shipped NAME"
};

// The text `name_or_path` names: a path (it holds a '/' or ends in .toml), else a name looked up
// in kProtocolDirs and the shipped copies. nullopt and `error` when there is none.
std::optional<DescriptionText> find_description(const std::string& name_or_path,
                                                std::string& error);
// The names of the descriptions built into the plugin.
std::vector<std::string_view> shipped_names();
// The shipped text of `name`, if there is one.
std::optional<std::string_view> shipped_text(std::string_view name);

// The description `protocol` names, read and validated: nullptr and `error` ("option protocol:
// SOURCE:LINE: key: what; ...", every error, one line) when it is not there or not valid. The
// same text read twice is the same description (cached for the process's lifetime).
std::shared_ptr<const Description> load_description(const std::string& protocol,
                                                    std::string& error);

}  // namespace drivegate::framed
