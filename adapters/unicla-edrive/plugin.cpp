// The unicla-edrive plugin descriptor: option schema, line defaults, device ids, the two
// factories and how `drivegate demo` shows the compressor.
#include <memory>
#include <optional>
#include <string>

#include "codec.h"
#include "drivegate/adapter.h"
#include "drivegate/addressed.h"
#include "driver.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::unicla {
namespace {

// "Device Address": 0x00 is the master's, 0xFF every device's; a drive has one of the others.
std::optional<std::uint8_t> device_id(std::uint32_t address, std::string& error) {
  if (address < kFirstDeviceId || address > kLastDeviceId) {
    error = "address: eDrive device ids are 1..254";
    return std::nullopt;
  }
  return static_cast<std::uint8_t>(address);
}

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  const auto d = addressed(env.options, env.address, error, parse_settings, device_id);
  if (!d) return nullptr;
  return std::make_unique<EDriveDriver>(d->address, env.poll_interval, d->settings);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  const auto d = addressed(env.options, env.address, error, parse_settings, device_id);
  if (!d) return nullptr;
  return std::make_unique<EDriveSimulator>(d->address, d->settings.byte_order);
}

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
    {
        .id = "unicla-edrive",
        .summary = "Unicla eDrive compressor, RS-485 interface V16",
        .line = kLine,
        .address_min = kFirstDeviceId,
        .address_max = kLastDeviceId,
        .default_address = kDefaultDeviceId,
        // Not streaming: "all transfers are required to be master initiated".
        .create_driver = &create_driver,
        .create_simulator = &create_simulator,
        // Default options; half the simulated drive's 6000 rpm running limit.
        .demo = {.running_rpm = 3000},
    },
    kOptionSchema);

}  // namespace drivegate::unicla
