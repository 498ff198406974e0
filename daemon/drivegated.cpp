// drivegated: the gateway daemon. See drivegated(8).
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>
#include <string_view>

#include "app/daemon.h"
#include "app/logging.h"
#include "config/config_loader.h"
#include "gateway/gateway.h"
#include "modbus/tls.h"

namespace {

constexpr const char* kUsage =
    "usage: drivegated --config FILE [--listen HOST:PORT] [--plugin-dir DIR] [--log-level LEVEL]\n"
    "       drivegated --check-config FILE [--plugin-dir DIR]\n"
    "       drivegated --version | --help\n"
    "\n"
    "Polls the drives configured in FILE on their serial lines and serves them as one Modbus\n"
    "TCP server. --listen replaces the address of the first listener (its allow list and access\n"
    "level stay). LEVEL: trace, debug, info (default), warn, error.\n";

int usage_error(const std::string& what) {
  std::cerr << "drivegated: " << what << "\n" << kUsage;
  return 2;
}

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
      if (!l.options.policy.tls) continue;
      std::string error;
      if (!drivegate::modbus::make_tls_context(*l.options.policy.tls, error)) {
        errors.push_back(file.string() + ":" + std::to_string(l.line) + ": listener " +
                         l.options.name() + ": " + error);
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

}  // namespace

int main(int argc, char** argv) {
  drivegate::DaemonOptions options;
  std::optional<std::filesystem::path> check;
  auto level = spdlog::level::info;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const auto value = [&](std::string_view name) -> std::optional<std::string> {
      if (i + 1 >= argc) return std::nullopt;
      (void)name;
      return std::string(argv[++i]);
    };
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage;
      return 0;
    }
    if (arg == "--version") {
      std::cout << "drivegated " << DRIVEGATE_VERSION << "\n";
      return 0;
    }
    if (arg == "--config" || arg == "-c") {
      auto v = value(arg);
      if (!v) return usage_error("--config needs a file");
      options.config = *v;
    } else if (arg == "--check-config") {
      auto v = value(arg);
      if (!v) return usage_error("--check-config needs a file");
      check = *v;
    } else if (arg == "--plugin-dir") {
      auto v = value(arg);
      if (!v) return usage_error("--plugin-dir needs a directory");
      options.plugin_dir = *v;
    } else if (arg == "--listen") {
      auto v = value(arg);
      auto listen = v ? drivegate::parse_listen(*v) : std::nullopt;
      if (!listen) return usage_error("--listen needs HOST:PORT (e.g. 127.0.0.1:1502)");
      options.listen = std::move(*listen);
    } else if (arg == "--log-level") {
      auto v = value(arg);
      auto parsed = v ? drivegate::parse_log_level(*v) : std::nullopt;
      if (!parsed) return usage_error("--log-level needs trace, debug, info, warn or error");
      level = *parsed;
    } else {
      return usage_error("unknown argument '" + std::string(arg) + "'");
    }
  }
  const auto plugin_dir =
      options.plugin_dir.empty() ? drivegate::default_plugin_dir() : options.plugin_dir;
  if (check) return check_config(*check, plugin_dir);
  if (options.config.empty()) return usage_error("--config FILE is required");
  try {
    drivegate::Daemon daemon(std::move(options), drivegate::make_logger("drivegated", level));
    return daemon.run();
  } catch (const std::exception& e) {
    std::cerr << "drivegated: fatal: " << e.what() << "\n";
    return 1;
  }
}
