// The test-drive plugin descriptor (codec.h): the drive the core's end-to-end tests run on. Built
// into the build's plugin directory for the tests, never installed or packaged.
#include <memory>
#include <optional>
#include <string>

#include "drivegate/adapter.h"
#include "driver.h"
#include "simulator.h"

namespace drivegate::testdrive {
namespace {

constexpr std::uint32_t kAddressMin = 1;
constexpr std::uint32_t kAddressMax = 247;

std::optional<std::uint8_t> address_of(std::uint32_t address, std::string& error) {
  if (address < kAddressMin || address > kAddressMax) {
    error = "address: test-drive addresses are 1..247";
    return std::nullopt;
  }
  return static_cast<std::uint8_t>(address);
}

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  const auto address = address_of(env.address, error);
  if (!address) return nullptr;
  return std::make_unique<TestDriveDriver>(*address, env.poll_interval,
                                           parse_settings(env.options));
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  const auto address = address_of(env.address, error);
  if (!address) return nullptr;
  return std::make_unique<TestDriveSimulator>(*address);
}

}  // namespace
}  // namespace drivegate::testdrive

extern "C" DRIVEGATE_EXPORT constinit const drivegate::AdapterDescriptor drivegate_adapter = {
    .api_version = drivegate::kAdapterApiVersion,
    .id = "test-drive",
    .summary = "a made-up drive for drivegate's own tests (never installed)",
    .options = drivegate::testdrive::kOptionSchema.data(),
    .option_count = drivegate::testdrive::kOptionSchema.size(),
    .line = {.baud = 9600,
             .parity = drivegate::Parity::none,
             .data_bits = 8,
             .stop_bits = 1,
             .echo = false},
    .address_min = drivegate::testdrive::kAddressMin,
    .address_max = drivegate::testdrive::kAddressMax,
    .default_address = 1,
    .streaming = false,
    .create_driver = &drivegate::testdrive::create_driver,
    .create_simulator = &drivegate::testdrive::create_simulator,
    .demo = {.options = nullptr, .option_count = 0, .running_rpm = 1500},
    .actions = nullptr,
    .action_count = 0,
};
