// drivegated's command line (drivegated(8)): its table of options, which is also its --help and
// what the man page documents, and what a command line asks the daemon to do.
#pragma once

#include <spdlog/common.h>

#include <filesystem>
#include <span>
#include <string>
#include <variant>

#include "app/daemon.h"
#include "base/command_line.h"

namespace drivegate {

enum class DaemonAction : std::uint8_t { run, check_config, help, version };

struct DaemonArgs {
  DaemonAction action = DaemonAction::run;
  DaemonOptions options;        // run: --config, --plugin-dir, --listen, --state-dir
  std::filesystem::path check;  // check_config: the file
  spdlog::level::level_enum log_level = spdlog::level::info;
};

// Every option drivegated takes; drivegated(8) lists each of them.
std::span<const Option> daemon_option_table();
CommandLine daemon_command_line();

// What `args` (the words after the program's name) ask for; otherwise the one-line usage error
// ("option '--config' needs a value (FILE)", "--log-level needs trace, ..., not 'loud'").
std::variant<DaemonArgs, std::string> parse_daemon_args(std::span<const std::string> args);

// --state-dir when given, else systemd's $STATE_DIRECTORY (`state_directory`: its value, or null
// when unset; the first of a colon-separated list), else nothing.
std::filesystem::path resolve_state_dir(const std::filesystem::path& option,
                                        const char* state_directory);

}  // namespace drivegate
