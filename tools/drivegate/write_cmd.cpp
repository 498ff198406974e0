// drivegate write: write points of one device directly on its serial line (daemon stopped), with
// maintenance-only points enabled.
#include <iostream>

#include "commands.h"
#include "config/config_loader.h"
#include "point_writes.h"

namespace drivegate::cli {

namespace {

constexpr const char* kUsage =
    "usage: drivegate write --config FILE --device NAME [--timeout-ms N] POINT=VALUE...\n"
    "\n"
    "Opens only that device's bus (stop the daemon first if it owns the port), waits for the\n"
    "device to come online, then writes each point in order and waits for the device to confirm\n"
    "it. VALUE is a number or one of the point's labels (e.g. command=run_forward).\n";

}  // namespace

int write(std::span<const std::string_view> args) {
  ArgReader r("write", args);
  DeviceArgs device;
  std::vector<Assignment> writes;
  while (!r.done()) {
    const auto arg = r.next();
    if (arg == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (!arg.starts_with("--")) {
      auto a = parse_assignment(arg);
      if (!a) return r.usage("'" + std::string(arg) + "' is not POINT=VALUE", kUsage);
      writes.push_back(std::move(*a));
      continue;
    }
    if (const int rc = device.read(r, arg, kUsage); rc != 0) return rc;
  }
  if (device.config.empty() || device.name.empty()) {
    return r.usage("--config and --device are required", kUsage);
  }
  if (writes.empty()) return r.usage("nothing to write", kUsage);
  const PluginRegistry plugins = load_plugins(device.plugin_dir);
  auto result = load_config(device.config, plugins);
  for (const auto& e : result.errors) std::cerr << e << "\n";
  if (!result.config) return 1;
  return run_point_writes({&*result.config, &plugins, device.name, writes, device.timeout, ""});
}

}  // namespace drivegate::cli
