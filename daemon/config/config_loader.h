// Reads and validates the TOML configuration. Every error names the file, the line and the key;
// all errors are collected, so a user fixes a file in one pass rather than one error per run.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "config.h"
#include "plugin/plugins.h"

namespace drivegate {

struct ConfigResult {
  std::optional<Config> config;
  std::vector<std::string> errors;    // "FILE:LINE: key: what is wrong"
  std::vector<std::string> warnings;  // the same shape: valid, but probably not meant
};

// "host:port", "[v6]:port" or ":port" (every IPv4 interface); nullopt when it is none of these.
std::optional<ListenAddress> parse_listen(std::string_view text);

ConfigResult load_config(const std::filesystem::path& path, const PluginRegistry& plugins);
// Only [server], [[listener]] and [http] of the file at `path`, read and checked as load_config()
// reads them (its other tables are not looked into, warnings are left out): where the running
// daemon's HTTP side is, for the tools that talk to it, whatever adapters its devices name.
ConfigResult load_http_config(const std::filesystem::path& path);
// The same from text already in memory; `source_name` stands for the file in messages.
ConfigResult parse_config(std::string_view text, const std::string& source_name,
                          const PluginRegistry& plugins);

}  // namespace drivegate
