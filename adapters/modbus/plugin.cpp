// The modbus plugin descriptor: option schema, line defaults, the two factories and how
// `drivegate demo` shows the device (the example VFD, profiles/example-vfd.toml).
#include <memory>
#include <string>

#include "drivegate/adapter.h"
#include "drivegate/addressed.h"
#include "driver.h"
#include "passthrough.h"
#include "settings.h"
#include "simulator.h"
#include "specialise.h"

namespace drivegate::modbus_device {

extern "C" DRIVEGATE_EXPORT const AdapterDescriptor drivegate_adapter;

namespace {

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  const auto address = device_address(env.address, error);
  if (!address) return nullptr;
  if (env.options.boolean("passthrough")) {
    auto pass = parse_passthrough(env.options, error);
    if (!pass) return nullptr;
    return std::make_unique<PassthroughDriver>(*address, *pass, env.char_time, env.poll_interval);
  }
  auto settings = parse_settings(env.options, error);
  if (!settings) return nullptr;
  if (env.bus_line &&
      !line_agrees(settings->profile, settings->profile_source, *env.bus_line, error)) {
    return nullptr;
  }
  return std::make_unique<ModbusDriver>(
      *address, std::move(settings->profile),
      Timing{settings->attempts, settings->comm_timeout, env.char_time}, env.poll_interval,
      std::move(settings->files_read));
}

// A pass-through device's simulator is a slave like any other: it serves the profile its options
// name (the default one unless --set profile=NAME), a required option not set at its example.
std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  const auto parse = [](const Options& options, std::string& why) {
    return parse_settings(options, why, Unset::example);
  };
  auto d = addressed(env.options, env.address, error, parse, device_address);
  if (!d) return nullptr;
  return std::make_unique<ModbusSimulator>(d->address, std::move(d->settings.profile));
}

constexpr OptionSetting kDemoOptions[] = {{"profile", "example-vfd"}};

const AdapterDescriptor* specialise_device(const Options& options, std::string& error) {
  return specialise(drivegate_adapter, options, error);
}

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
    {
        .id = "modbus",
        .summary = "any Modbus RTU / ASCII slave, described by a profile (docs/profiles.md)",
        // Serial Line 2.5.1: 19200 baud and even parity are the defaults every device must offer.
        .line =
            {.baud = 19200, .parity = Parity::even, .data_bits = 8, .stop_bits = 1, .echo = false},
        // Serial Line 2.2: 1..247 are slaves (0, the broadcast, is never polled).
        .address_min = 1,
        .address_max = 247,
        .default_address = 1,
        // Not streaming: a slave only ever answers.
        .create_driver = &create_driver,
        .create_simulator = &create_simulator,
        .demo = demo_setup(kDemoOptions, 1500),
        // A profile's own options ([options.NAME]) join the schema of its devices.
        .specialise = &specialise_device,
    },
    kOptionSchema);

}  // namespace drivegate::modbus_device
