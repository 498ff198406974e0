// drivegate write: write points of one device directly on its serial line (daemon stopped), with
// maintenance-only points enabled.
#include <iostream>

#include "commands.h"
#include "config/config_loader.h"
#include "point_writes.h"

namespace drivegate::cli {

namespace {

constexpr Option kOptions[] = {
    kConfigOption, kDeviceOption, kTimeoutOption, kPluginDirOption, kHelpOption,
};

}  // namespace

int write(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate write", kOptions, {"-c FILE -d NAME [-t N] [-p DIR] POINT=VALUE..."},
      "Opens only that device's bus (stop the daemon first if it owns the port), waits for the\n"
      "device to come online, then writes each point in order and waits for the device to confirm\n"
      "it. VALUE is a number or one of the point's labels (e.g. command=run_forward).");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  const auto device = device_args(cli, *parsed);
  if (!device) return 2;
  std::vector<Assignment> writes;
  for (const auto& arg : parsed->operands) {
    auto a = parse_assignment(arg);
    if (!a) return cli.usage_error("'" + arg + "' is not POINT=VALUE");
    writes.push_back(std::move(*a));
  }
  if (writes.empty()) return cli.usage_error("nothing to write");
  const PluginRegistry plugins = load_plugins(device->plugin_dir);
  auto result = load_config(device->config, plugins);
  for (const auto& e : result.errors) std::cerr << e << "\n";
  if (!result.config) return 1;
  return run_point_writes({&*result.config, &plugins, device->name, writes, device->timeout, ""});
}

}  // namespace drivegate::cli
