// drivegated: the gateway daemon. See drivegated(8).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "app/daemon.h"
#include "app/daemon_args.h"
#include "app/logging.h"
#include "config/config_loader.h"
#include "gateway/gateway.h"
#include "modbus/options_from_config.h"
#include "modbus/tls.h"

namespace {

// Validates the configuration as the daemon would, including the adapters' own checks.
int check_config(const std::filesystem::path& file, const std::filesystem::path& plugin_dir) {
  drivegate::PluginRegistry plugins;
  for (const auto& refused : plugins.load_directory(plugin_dir)) {
    std::cerr << "drivegated: plugin " << refused << "\n";
  }
  auto result = drivegate::load_config(file, plugins);
  std::vector<std::string> errors = std::move(result.errors);
  if (result.config) {
    boost::asio::io_context io;
    auto log = drivegate::make_logger("check", spdlog::level::off);
    drivegate::Gateway::build(io, *result.config, plugins, log, errors);
    // The TLS files as the listener will read them (permissions, PEM, key matching certificate).
    for (const auto& l : result.config->listeners) {
      if (!l.policy.tls) continue;
      std::string error;
      if (!drivegate::modbus::make_tls_context(drivegate::modbus::tls_options(*l.policy.tls),
                                               error)) {
        errors.push_back(file.string() + ":" + std::to_string(l.line) + ": listener " +
                         drivegate::listener_name(l) + ": " + error);
      }
    }
  }
  for (const auto& w : result.warnings) std::cerr << "warning: " << w << "\n";
  for (const auto& e : errors) std::cerr << e << "\n";
  if (!errors.empty()) {
    std::cerr << file.string() << ": " << errors.size() << " error"
              << (errors.size() == 1 ? "" : "s") << "\n";
    return 1;
  }
  std::cout << file.string() << ": OK (" << result.config->devices.size() << " devices on "
            << result.config->buses.size() << " buses, " << result.config->listeners.size()
            << " listener" << (result.config->listeners.size() == 1 ? "" : "s") << ")\n";
  return 0;
}

int run(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  auto parsed = drivegate::parse_daemon_args(args);
  if (const auto* error = std::get_if<std::string>(&parsed)) {
    return drivegate::daemon_command_line().usage_error(*error);
  }
  auto& a = std::get<drivegate::DaemonArgs>(parsed);
  switch (a.action) {
    case drivegate::DaemonAction::help:
      std::cout << drivegate::daemon_command_line().help();
      return 0;
    case drivegate::DaemonAction::version:
      std::cout << "drivegated " << DRIVEGATE_VERSION << "\n";
      return 0;
    case drivegate::DaemonAction::check_config:
      return check_config(a.check, a.options.plugin_dir.empty() ? drivegate::default_plugin_dir()
                                                                : a.options.plugin_dir);
    case drivegate::DaemonAction::run:
      break;
  }
  a.options.state_dir =
      drivegate::resolve_state_dir(a.options.state_dir, std::getenv("STATE_DIRECTORY"));
  drivegate::Daemon daemon(std::move(a.options), drivegate::make_logger("drivegated", a.log_level));
  return daemon.run();
}

}  // namespace

// Whatever throws, from reading the arguments to the event loop's last handler, ends here: a
// message on stderr (the journal) and exit status 1, for systemd to restart the service.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "drivegated: fatal: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "drivegated: fatal: an unknown exception\n";
  }
  return 1;
}
