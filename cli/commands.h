// The `drivegate` subcommands. Each takes the arguments after its own name and returns the
// process exit code: 0 success, 1 failure, 2 usage error. Each parses them with one table of
// options (base/command_line.h) that is also its --help; drivegate(1) documents the same.
#pragma once

#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "base/command_line.h"
#include "config/config.h"
#include "plugin/plugins.h"
#include "point_writes.h"

namespace drivegate::cli {

int regmap(std::span<const std::string> args);
int sim(std::span<const std::string> args);
int demo(std::span<const std::string> args);
int write(std::span<const std::string> args);
int action(std::span<const std::string> args);
int capture(std::span<const std::string> args);
int events(std::span<const std::string> args);
int dcmd(std::span<const std::string> args);
int scan(std::span<const std::string> args);      // built with the modbus adapter (DRIVEGATE_SCAN)
int profile(std::span<const std::string> args);   // the same (DRIVEGATE_SCAN)
int protocol(std::span<const std::string> args);  // with the framed adapter (DRIVEGATE_PROTOCOL)

// The options several subcommands share, with one wording wherever they appear.
inline constexpr Option kHelpOption{"help", 'h', nullptr, "print this help and exit"};
inline constexpr Option kPluginDirOption{
    "plugin-dir", 'p', "DIR", "load the adapter plugins from DIR instead of the installed ones"};
inline constexpr Option kConfigOption{"config", 'c', "FILE", "the configuration (drivegate.toml)"};
inline constexpr Option kDeviceOption{"device", 'd', "NAME", "the device of FILE to work on"};
inline constexpr Option kTimeoutOption{
    "timeout-ms", 't', "N",
    "how long to wait for the device to come online and for each write (1..3600000 ms, default "
    "10000)"};

// Parses `args` with `cli`. nullopt when the command ends here: after printing its help
// (--help; `exit_status` 0) or a usage error naming what is wrong (`exit_status` 2).
std::optional<ParsedArgs> parse_command(const CommandLine& cli, std::span<const std::string> args,
                                        int& exit_status);

// What `write`, `action` and `dcmd` share: --config, --device, --plugin-dir, --timeout-ms.
struct DeviceArgs {
  std::filesystem::path config;
  std::filesystem::path plugin_dir;
  std::string name;
  Millis timeout{10'000};
};
// Reads them from `parsed` (a table with the four options above); nullopt after a usage error
// (printed; the status to exit with is 2).
std::optional<DeviceArgs> device_args(const CommandLine& cli, const ParsedArgs& parsed);

// "POINT=VALUE" (or "KEY=VALUE"); nullopt when there is no '=' or nothing before it.
std::optional<Assignment> parse_assignment(std::string_view arg);

// What `write` and `dcmd` share: their DeviceArgs, the NAME=VALUE operands (at least one), and
// the configuration, loaded with the plugins.
struct DeviceCommand {
  DeviceArgs device;
  std::vector<Assignment> writes;
  PluginRegistry plugins;
  Config config;
};
// From `parsed` (a table with the four options of DeviceArgs); nullopt after a usage error
// (`form`: what an operand must look like, "POINT=VALUE"; `exit_status` 2) or a configuration
// that does not load (its errors printed; 1).
std::optional<DeviceCommand> device_command(const CommandLine& cli, const ParsedArgs& parsed,
                                            std::string_view form, int& exit_status);

// Loads the plugins from --plugin-dir or the default place, reporting refusals on stderr.
PluginRegistry load_plugins(const std::filesystem::path& dir);

}  // namespace drivegate::cli
