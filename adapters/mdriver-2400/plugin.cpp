// The mdriver-2400 plugin descriptor: option schema, line defaults, the two factories and how
// `drivegate demo` shows the compressor.
#include <memory>
#include <string>

#include "codec.h"
#include "drivegate/adapter.h"
#include "drivegate/addressed.h"
#include "driver.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::mdriver {
namespace {

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  const auto d = addressed(env.options, env.address, error, parse_settings, device_address);
  if (!d) return nullptr;
  return std::make_unique<Mdriver2400Driver>(d->address, d->settings, env.poll_interval);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  const auto d = addressed(env.options, env.address, error, parse_settings, device_address);
  if (!d) return nullptr;
  return std::make_unique<Mdriver2400Simulator>(d->address);
}

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
    {
        .id = "mdriver-2400",
        .summary = "compressor motor driver, sum-0x55 frames (Japanese spec)",
        .line = kLine,
        // Section 2: one-byte addresses; section 3: slave (driver) address [01].
        .address_min = 0,
        .address_max = 255,
        .default_address = 0x01,
        // Not streaming: section 2, the driver only ever answers the master.
        .create_driver = &create_driver,
        .create_simulator = &create_simulator,
        // Default options; code 0x40 of the conversion table, 1149 rpm.
        .demo = {.running_rpm = 1149},
    },
    kOptionSchema);

}  // namespace drivegate::mdriver
