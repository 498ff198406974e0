// The plugin descriptor of the Unicla eDrive adapter.
#include "drivegate/adapter.h"
#include "driver.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::unicla {
namespace {

// "Device ID: uint8, 0x00 is reserved for master device id"; 0xFF is the global address.
constexpr std::uint32_t kAddressMin = 1;
constexpr std::uint32_t kAddressMax = 254;
constexpr std::uint32_t kDefaultAddress = 1;  // "Device ID ... Default Value 0x01"

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  if (env.address < kAddressMin || env.address > kAddressMax) {
    error = "address: eDrive device ids are 1..254";
    return nullptr;
  }
  const auto settings = parse_settings(env.options, error);
  if (!settings) return nullptr;
  return std::make_unique<EDriveDriver>(static_cast<std::uint8_t>(env.address), env.poll_interval,
                                        *settings);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  if (env.address < kAddressMin || env.address > kAddressMax) {
    error = "address: eDrive device ids are 1..254";
    return nullptr;
  }
  const auto settings = parse_settings(env.options, error);
  if (!settings) return nullptr;
  return std::make_unique<EDriveSimulator>(static_cast<std::uint8_t>(env.address),
                                           settings->byte_order);
}

}  // namespace
}  // namespace drivegate::unicla

extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
    drivegate::kAdapterApiVersion,
    "unicla-edrive",
    "Unicla eDrive compressor, RS-485 interface V16",
    drivegate::unicla::kOptionSchema.data(),
    drivegate::unicla::kOptionSchema.size(),
    // "Communications Settings": 8 data bits, 1 stop bit, no parity; "Baud Rate ... 19200".
    {19200, drivegate::Parity::none, 8, 1, false},
    drivegate::unicla::kAddressMin,
    drivegate::unicla::kAddressMax,
    drivegate::unicla::kDefaultAddress,
    false,  // "all transfers are required to be master initiated"
    &drivegate::unicla::create_driver,
    &drivegate::unicla::create_simulator,
};
