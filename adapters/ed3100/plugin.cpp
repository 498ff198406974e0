// The ed3100 plugin descriptor: option schema, line defaults, the two factories and how
// `drivegate demo` shows the drive.
#include <memory>
#include <string>

#include "drivegate/adapter.h"
#include "drivegate/addressed.h"
#include "driver.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::ed3100 {
namespace {

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  auto d = addressed(env.options, env.address, error, parse_settings, device_address);
  if (!d) return nullptr;
  return std::make_unique<Ed3100Driver>(d->address, std::move(d->settings), env.poll_interval);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  const auto d = addressed(env.options, env.address, error, parse_settings, device_address);
  if (!d) return nullptr;
  return std::make_unique<Ed3100Simulator>(d->address, d->settings.sim_reply_form);
}

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
    {
        .id = "ed3100",
        .summary = "ED3100 variable-frequency drive, Modbus RTU with its 03 reply quirk",
        // The document offers 8N2, 8E1 and 8O1 and leaves the baud rate to a parameter table it
        // does not include: 9600 8E1 is drivegate's default (README.md, "Choices", 1).
        .line =
            {.baud = 9600, .parity = Parity::even, .data_bits = 8, .stop_bits = 1, .echo = false},
        // Document, "Address": 1..31 drives, 0 the broadcast, factory setting 01.
        .address_min = 0,
        .address_max = 31,
        .default_address = 1,
        // Not streaming: document, "communication protocol": the drive only ever answers.
        .create_driver = &create_driver,
        .create_simulator = &create_simulator,
        // Default options; a typical running speed, 50 Hz at the default 4 poles.
        .demo = {.running_rpm = 1500},
    },
    kOptionSchema);

}  // namespace drivegate::ed3100
