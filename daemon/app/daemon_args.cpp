#include "app/daemon_args.h"

#include "app/logging.h"
#include "config/config_loader.h"

namespace drivegate {
namespace {

constexpr Option kOptions[] = {
    {"config", 'c', "FILE", "run the gateway configured in FILE"},
    {"check-config", 0, "FILE",
     "validate FILE as the daemon would (every adapter's checks and the listeners' TLS files "
     "included) without opening a port or a socket, then exit: 0 valid, 1 not"},
    {"listen", 0, "HOST:PORT",
     "listen there instead of at the first listener's address (its allow list, access level "
     "and TLS settings stay); [::]:502 for IPv6"},
    {"plugin-dir", 'p', "DIR", "load the adapter plugins from DIR instead of the installed ones"},
    {"state-dir", 0, "DIR",
     "keep what must survive a restart (the Sparkplug bdSeq) in DIR; default: $STATE_DIRECTORY, "
     "which systemd sets from the unit's StateDirectory= (/var/lib/drivegate)"},
    {"log-level", 'l', "LEVEL", "trace (every frame in hex), debug, info (default), warn or error"},
    {"version", 'V', nullptr, "print the version and exit"},
    {"help", 'h', nullptr, "print this help and exit"},
};

}  // namespace

std::span<const Option> daemon_option_table() {
  return kOptions;
}

CommandLine daemon_command_line() {
  return CommandLine(
      "drivegated", kOptions,
      {"-c FILE [--listen HOST:PORT] [-p DIR] [-l LEVEL]",
       "--check-config FILE [-p DIR]", "-V | -h"},
      "Polls the drives configured in FILE on their serial lines and serves them as one Modbus\n"
      "TCP server. SIGTERM or SIGINT stops every drive and exits 0; SIGHUP re-reads FILE.\n"
      "See drivegated(8) and drivegate.toml(5).");
}

std::variant<DaemonArgs, std::string> parse_daemon_args(std::span<const std::string> args) {
  const ParsedArgs parsed = daemon_command_line().parse(args);
  if (parsed.error) return *parsed.error;
  DaemonArgs out;
  if (parsed.has("help")) {
    out.action = DaemonAction::help;
    return out;
  }
  if (parsed.has("version")) {
    out.action = DaemonAction::version;
    return out;
  }
  if (!parsed.operands.empty()) return "unexpected argument '" + parsed.operands.front() + "'";
  if (const auto v = parsed.value("listen")) {
    auto listen = parse_listen(*v);
    if (!listen) return "--listen needs HOST:PORT (e.g. 127.0.0.1:1502), not '" + *v + "'";
    out.options.listen = std::move(*listen);
  }
  if (const auto v = parsed.value("log-level")) {
    const auto level = parse_log_level(*v);
    if (!level) return "--log-level needs trace, debug, info, warn or error, not '" + *v + "'";
    out.log_level = *level;
  }
  if (const auto v = parsed.value("plugin-dir")) out.options.plugin_dir = *v;
  if (const auto v = parsed.value("state-dir")) {
    if (v->empty()) return std::string("--state-dir needs a directory, not ''");
    out.options.state_dir = *v;
  }
  if (const auto v = parsed.value("check-config")) {
    out.action = DaemonAction::check_config;
    out.check = *v;
    return out;
  }
  const auto config = parsed.value("config");
  if (!config) return std::string("--config FILE is required");
  out.options.config = *config;
  return out;
}

std::filesystem::path resolve_state_dir(const std::filesystem::path& option,
                                        const char* state_directory) {
  if (!option.empty()) return option;
  if (state_directory == nullptr) return {};
  const std::string_view v(state_directory);
  return {std::string(v.substr(0, v.find(':')))};
}

}  // namespace drivegate
