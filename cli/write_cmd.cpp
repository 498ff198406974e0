// drivegate write: write points of one device directly on its serial line (daemon stopped), with
// maintenance-only points enabled.
#include "commands.h"
#include "point_writes.h"

namespace drivegate::cli {

namespace {

constexpr Option kWriteOptions[] = {
    kConfigOption, kDeviceOption, kTimeoutOption, kPluginDirOption, kHelpOption,
};

}  // namespace

int write(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate write", kWriteOptions, {"-c FILE -d NAME [-t N] [-p DIR] POINT=VALUE..."},
      "Opens only that device's bus (stop the daemon first if it owns the port), waits for the\n"
      "device to come online, then writes each point in order and waits for the device to confirm\n"
      "it. VALUE is a number or one of the point's labels (e.g. command=run_forward).");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  const auto job = device_command(cli, *parsed, "POINT=VALUE", exit_status);
  if (!job) return exit_status;
  return run_point_writes(
      {&job->config, &job->plugins, job->device.name, job->writes, job->device.timeout, ""});
}

}  // namespace drivegate::cli
