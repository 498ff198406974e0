// drivegate regmap: the register map of a configuration, as the daemon would serve it.
#include <iostream>

#include "commands.h"
#include "config/config_loader.h"
#include "gateway/gateway.h"
#include "regmap/regmap_format.h"

namespace drivegate::cli {

namespace {

constexpr Option kRegmapOptions[] = {
    kConfigOption,
    {"format", 'f', "FORMAT", "json (default), csv or md (Markdown)"},
    kPluginDirOption,
    kHelpOption,
};

}  // namespace

int regmap(std::span<const std::string> args) {
  const CommandLine cli("drivegate regmap", kRegmapOptions, {"-c FILE [-f json|csv|md] [-p DIR]"},
                        "Prints the Modbus register map the daemon serves for FILE: every unit's "
                        "points, table by\ntable, with their addresses and PLC references.");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  if (!parsed->operands.empty()) {
    return cli.usage_error("unexpected argument '" + parsed->operands.front() + "'");
  }
  const std::filesystem::path config_path = parsed->value("config").value_or("");
  const std::filesystem::path plugin_dir = parsed->value("plugin-dir").value_or("");
  RegmapFormat format = RegmapFormat::json;
  if (const auto v = parsed->value("format")) {
    if (*v == "json") {
      format = RegmapFormat::json;
    } else if (*v == "csv") {
      format = RegmapFormat::csv;
    } else if (*v == "md" || *v == "markdown") {
      format = RegmapFormat::markdown;
    } else {
      return cli.usage_error("--format must be json, csv or md, not '" + *v + "'");
    }
  }
  if (config_path.empty()) return cli.usage_error("--config FILE is required");
  const PluginRegistry plugins = load_plugins(plugin_dir);
  auto result = load_config(config_path, plugins);
  for (const auto& e : result.errors) std::cerr << e << "\n";
  if (!result.config) return 1;

  std::vector<DeviceRegisters> devices;
  for (const auto& dc : result.config->devices) {
    std::string error;
    auto driver = make_driver(dc, *plugins.find(dc.adapter, dc.options), false, error);
    if (!driver) {
      std::cerr << config_path.string() << ":" << dc.line << ": device " << error << "\n";
      return 1;
    }
    devices.push_back({&dc, RegisterMap(driver->points()), driver->forwards()});
  }
  std::vector<ServedOn> listeners;
  for (const auto& l : result.config->listeners) {
    listeners.push_back({listener_name(l), l.policy.word_order});
  }
  std::cout << format_regmap(devices, listeners, format);
  return 0;
}

}  // namespace drivegate::cli
