// The plugin contract. An adapter is a shared object exporting one data-only, versioned
// descriptor under the C symbol `drivegate_adapter`; the gateway finds it with dlsym, refuses any
// api_version but its own, validates the device options against `options`, and then only ever
// calls the two factories. adapters/README.md describes the folder every adapter has. A
// descriptor names only what is its adapter's own: the API version, an address range of none,
// not streaming, no actions and no specialiser are the defaults; describe() and demo_setup() take
// each array's pointer and size from the array.
//
//   namespace drivegate::nidec {
//   extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
//       {.id = "nidec-washer", .summary = ..., .line = ..., ...}, kOptionSchema);
//   }
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "drivegate/driver.h"
#include "drivegate/line.h"
#include "drivegate/simulator.h"

#define DRIVEGATE_EXPORT __attribute__((visibility("default")))

namespace drivegate {

// Bumped whenever anything in include/drivegate/ changes layout or meaning.
inline constexpr std::uint32_t kAdapterApiVersion = 8;
inline constexpr const char* kDescriptorSymbol = "drivegate_adapter";

// Returns nullptr and sets `error` (one line, naming the option) when the options are
// individually valid but do not make a device together.
using DriverFactory = std::unique_ptr<Driver> (*)(const DeviceEnv& env, std::string& error);
using SimulatorFactory = std::unique_ptr<Simulator> (*)(const SimEnv& env, std::string& error);

struct AdapterDescriptor;
// For an adapter whose devices each follow a description they name (framed: a protocol described
// in a file declares its own options, line, addresses and streaming): the descriptor of one
// device, given the options of this descriptor's own schema (defaults filled in). The core then
// reads that device's options, line and addresses from it, and creates its driver and simulator
// with its factories. Owned by the plugin for the process's lifetime. nullptr and `error` (one
// line, naming the option) when the options name nothing usable.
using Specialiser = const AdapterDescriptor* (*)(const Options& options, std::string& error);

// One option of a demo or test device, as text (parsed like the command line's --set).
struct OptionSetting {
  const char* name;
  const char* value;
};

// How `drivegate demo` shows the adapter: the options its simulated device and the gateway's
// device both get, and a speed typical of the machine it drives, which the demo runs it at.
struct DemoSetup {
  const OptionSetting* options = nullptr;
  std::size_t option_count = 0;
  std::int32_t running_rpm = 1000;
};

// A demo that sets `options`, each written once: `.demo = demo_setup(kDemoOptions, 2000)`.
constexpr DemoSetup demo_setup(std::span<const OptionSetting> options, std::int32_t running_rpm) {
  return {.options = options.data(), .option_count = options.size(), .running_rpm = running_rpm};
}

// A maintenance action, run with the daemon stopped: `drivegate action --config FILE --device
// NAME ACTION key=value...` writes maintenance point `<parameter_prefix><key>` for each key, in
// order, then 1 to `commit_point`, which carries the action out; when the drive or the driver's
// own validation refuses it, string point `message_point` says why. The validation lives in the
// adapter's driver, never in the tool.
struct MaintenanceAction {
  const char* name;              // "program"
  const char* summary;           // one line for `drivegate action --help`
  const char* parameter_prefix;  // "prog_"
  const char* commit_point;      // "prog_commit"
  const char* message_point;     // "prog_message"
};

struct AdapterDescriptor {
  std::uint32_t api_version = kAdapterApiVersion;  // the version the plugin was compiled against
  const char* id;
  const char* summary;
  const OptionSpec* options = nullptr;  // describe() sets both from the adapter's schema
  std::size_t option_count = 0;
  LineDefaults line;
  std::uint32_t address_min = 0;  // native address range; {0, 0}: the protocol has no address
  std::uint32_t address_max = 0;
  std::uint32_t default_address = 0;
  bool streaming = false;  // transmits unsolicited frames: must be the only device on its bus
  DriverFactory create_driver;
  SimulatorFactory create_simulator;
  DemoSetup demo;
  const MaintenanceAction* actions = nullptr;  // none for most adapters
  std::size_t action_count = 0;
  Specialiser specialise = nullptr;  // none for most adapters
};

// A plugin's descriptor with each array's pointer and size taken from the array, so the two
// cannot disagree: `describe({.id = ..., ...}, kOptionSchema)`, and `kActions` after it for an
// adapter with maintenance actions.
constexpr AdapterDescriptor describe(AdapterDescriptor d, std::span<const OptionSpec> schema,
                                     std::span<const MaintenanceAction> actions = {}) {
  d.options = schema.data();
  d.option_count = schema.size();
  d.actions = actions.data();
  d.action_count = actions.size();
  return d;
}

}  // namespace drivegate
