// drivegate action: a maintenance action an adapter offers (AdapterDescriptor::actions), carried
// out on one device with the daemon stopped. The tool knows no action: it writes the action's
// parameter points and its commit point, and the adapter's driver validates and performs it.
#include <iostream>

#include "commands.h"
#include "config/config_loader.h"
#include "gateway/gateway.h"
#include "point_writes.h"

namespace drivegate::cli {

namespace {

constexpr Option kActionOptions[] = {
    kConfigOption, kDeviceOption, kTimeoutOption, kPluginDirOption, kHelpOption,
};

const MaintenanceAction* find_action(const AdapterDescriptor& a, std::string_view name) {
  for (std::size_t i = 0; i < a.action_count; ++i) {
    if (name == a.actions[i].name) return &a.actions[i];
  }
  return nullptr;
}

// The action's parameters: the maintenance points named with its prefix, but its commit and
// message points.
std::vector<const MappedPoint*> parameters(const RegisterMap& map, const MaintenanceAction& a) {
  std::vector<const MappedPoint*> out;
  for (const auto& p : map.points()) {
    const std::string& n = p.spec.name;
    if (n.starts_with(a.parameter_prefix) && n != a.commit_point && n != a.message_point &&
        p.spec.access() == Access::read_write) {
      out.push_back(&p);
    }
  }
  return out;
}

int list_actions(const AdapterDescriptor& adapter, const DeviceConfig& dc) {
  if (adapter.action_count == 0) {
    std::cout << "adapter '" << adapter.id << "' offers no maintenance action\n";
    return 0;
  }
  std::string error;
  auto driver = make_driver(dc, adapter, /*maintenance=*/true, error);
  if (!driver) {
    std::cerr << "drivegate action: " << error << "\n";
    return 1;
  }
  const RegisterMap map(driver->points());
  for (std::size_t i = 0; i < adapter.action_count; ++i) {
    const MaintenanceAction& a = adapter.actions[i];
    std::cout << a.name << ": " << a.summary << "\n";
    const std::size_t prefix = std::string_view(a.parameter_prefix).size();
    for (const MappedPoint* p : parameters(map, a)) {
      std::cout << "  " << p->spec.name.substr(prefix) << "=VALUE";
      if (!p->spec.unit.empty()) std::cout << " (" << p->spec.unit << ")";
      std::cout << "  " << p->spec.description << "\n";
    }
  }
  return 0;
}

}  // namespace

int action(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate action", kActionOptions, {"-c FILE -d NAME [-t N] [-p DIR] [ACTION KEY=VALUE...]"},
      "Runs a maintenance action of the device's adapter (stop the daemon first if it owns the\n"
      "port): each KEY=VALUE sets one of the action's parameters, then the adapter validates them\n"
      "and carries the action out, confirmed by the device. Without ACTION, lists the actions of\n"
      "the device's adapter and their parameters.");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  const auto device = device_args(cli, *parsed);
  if (!device) return 2;
  std::string name;
  std::vector<Assignment> params;
  for (const auto& arg : parsed->operands) {
    if (name.empty()) {
      name = arg;
      continue;
    }
    auto a = parse_assignment(arg);
    if (!a) return cli.usage_error("'" + arg + "' is not KEY=VALUE");
    params.push_back(std::move(*a));
  }
  const PluginRegistry plugins = load_plugins(device->plugin_dir);
  auto result = load_config(device->config, plugins);
  for (const auto& e : result.errors) std::cerr << e << "\n";
  if (!result.config) return 1;
  const auto dc = std::find_if(result.config->devices.begin(), result.config->devices.end(),
                               [&](const DeviceConfig& d) { return d.name == device->name; });
  if (dc == result.config->devices.end()) {
    std::cerr << "drivegate action: no device '" << device->name << "' in "
              << device->config.string() << "\n";
    return 1;
  }
  const AdapterDescriptor& adapter = *plugins.find(dc->adapter, dc->options);
  if (name.empty()) return list_actions(adapter, *dc);
  const MaintenanceAction* a = find_action(adapter, name);
  if (a == nullptr) {
    std::cerr << "drivegate action: adapter '" << adapter.id << "' has no action '" << name
              << "' (`drivegate action --config FILE --device NAME` lists them)\n";
    return 1;
  }
  if (params.empty()) return cli.usage_error("no parameters given for action '" + name + "'");
  std::vector<Assignment> writes;
  writes.reserve(params.size() + 1);
  for (const auto& p : params) writes.push_back({a->parameter_prefix + p.point, p.value});
  writes.push_back({a->commit_point, "1"});
  return run_point_writes(
      {&*result.config, &plugins, device->name, writes, device->timeout, a->message_point});
}

}  // namespace drivegate::cli
