// Reads and validates the TOML configuration. Every error names the file, the line and the key;
// all errors are collected, so a user fixes a file in one pass rather than one error per run.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config.h"
#include "plugins.h"

namespace drivegate {

struct ConfigResult {
  std::optional<Config> config;
  std::vector<std::string> errors;  // "FILE:LINE: key: what is wrong"
};

// "host:port", "[v6]:port" or ":port" into `out`; false when it is none of these.
bool parse_listen(const std::string& text, ServerConfig& out);

ConfigResult load_config(const std::filesystem::path& path, const PluginRegistry& plugins);
// The same from text already in memory; `source_name` stands for the file in messages.
ConfigResult parse_config(std::string_view text, const std::string& source_name,
                          const PluginRegistry& plugins);

}  // namespace drivegate
