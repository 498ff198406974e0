// The plugin contract. An adapter is a shared object exporting one data-only, versioned
// descriptor under the C symbol `drivegate_adapter`; the gateway finds it with dlsym, refuses any
// api_version but its own, validates the device options against `options`, and then only ever
// calls the two factories.
//
//   extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
//       drivegate::kAdapterApiVersion, "nidec-washer", "Nidec washer inverter (spec V07)", ...};
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "drivegate/driver.h"
#include "drivegate/simulator.h"

#define DRIVEGATE_EXPORT __attribute__((visibility("default")))

namespace drivegate {

// Bumped whenever anything in include/drivegate/ changes layout or meaning.
inline constexpr std::uint32_t kAdapterApiVersion = 1;
inline constexpr const char* kDescriptorSymbol = "drivegate_adapter";

enum class Parity : std::uint8_t { none, even, odd };

// The device's native line settings, used for a [[bus]] that does not set its own.
struct LineDefaults {
  std::uint32_t baud;
  Parity parity;
  std::uint8_t data_bits;
  std::uint8_t stop_bits;
  bool echo;  // one-wire line: the master hears its own bytes
};

// Returns nullptr and sets `error` (one line, naming the option) when the options are
// individually valid but do not make a device together.
using DriverFactory = std::unique_ptr<Driver> (*)(const DeviceEnv& env, std::string& error);
using SimulatorFactory = std::unique_ptr<Simulator> (*)(const SimEnv& env, std::string& error);

struct AdapterDescriptor {
  std::uint32_t api_version;
  const char* id;
  const char* summary;
  const OptionSpec* options;
  std::size_t option_count;
  LineDefaults line;
  std::uint32_t address_min;  // native address range; {0, 0}: the protocol has no address
  std::uint32_t address_max;
  std::uint32_t default_address;
  bool streaming;  // transmits unsolicited frames: must be the only device on its bus
  DriverFactory create_driver;
  SimulatorFactory create_simulator;
};

}  // namespace drivegate
