// drivegate regmap: the register map of a configuration, as the daemon would serve it.
#include <iostream>

#include "commands.h"
#include "config/config_loader.h"
#include "format/regmap_format.h"
#include "gateway/gateway.h"

namespace drivegate::cli {

namespace {
constexpr const char* kUsage =
    "usage: drivegate regmap --config FILE [--format json|csv|md] [--plugin-dir DIR]\n";
}

int regmap(std::span<const std::string_view> args) {
  ArgReader r("regmap", args);
  std::filesystem::path config_path;
  std::filesystem::path plugin_dir;
  RegmapFormat format = RegmapFormat::json;
  while (!r.done()) {
    const auto arg = r.next();
    if (arg == "--help") {
      std::cout << kUsage;
      return 0;
    }
    auto v = r.value(arg);
    if (!v) return 2;
    if (arg == "--config") {
      config_path = *v;
    } else if (arg == "--plugin-dir") {
      plugin_dir = *v;
    } else if (arg == "--format") {
      if (*v == "json") {
        format = RegmapFormat::json;
      } else if (*v == "csv") {
        format = RegmapFormat::csv;
      } else if (*v == "md" || *v == "markdown") {
        format = RegmapFormat::markdown;
      } else {
        return r.usage("--format must be json, csv or md", kUsage);
      }
    } else {
      return r.usage("unknown argument '" + std::string(arg) + "'", kUsage);
    }
  }
  if (config_path.empty()) return r.usage("--config FILE is required", kUsage);
  const PluginRegistry plugins = load_plugins(plugin_dir);
  auto result = load_config(config_path, plugins);
  for (const auto& e : result.errors) std::cerr << e << "\n";
  if (!result.config) return 1;

  std::vector<DeviceRegisters> devices;
  for (const auto& dc : result.config->devices) {
    std::string error;
    auto driver = make_driver(dc, *plugins.find(dc.adapter), false, error);
    if (!driver) {
      std::cerr << config_path.string() << ":" << dc.line << ": device " << error << "\n";
      return 1;
    }
    devices.push_back({&dc, RegisterMap(driver->points())});
  }
  std::cout << format_regmap(devices, format);
  return 0;
}

}  // namespace drivegate::cli
