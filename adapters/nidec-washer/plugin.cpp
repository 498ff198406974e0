// The nidec-washer plugin descriptor: option schema, line defaults, the two factories and how
// `drivegate demo` shows the washer.
#include <array>
#include <memory>
#include <string>

#include "codec.h"
#include "drivegate/adapter.h"
#include "driver.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::nidec {
namespace {

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  const auto settings = parse_settings(env.options, error);
  if (!settings) return nullptr;
  return std::make_unique<NidecWasherDriver>(*settings, env.poll_interval);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  // The options only shape the master's frames (the ping's platform and empty raw weight, 5.1),
  // but a simulator is refused for the same options a device is.
  if (!parse_settings(env.options, error)) return nullptr;
  return std::make_unique<NidecWasherSimulator>();
}

// `drivegate demo`: a 7 kg washer (5.1: platform 0x07), rotating at 800 rpm.
constexpr std::array<OptionSetting, 1> kDemoOptions = {{{"platform", "7"}}};

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
    {
        .id = "nidec-washer",
        .summary = "Nidec washing-machine inverter, Elaraby bus protocol spec V07",
        .line = kLine,  // section 3: 4800 8O1; section 2: one wire
        // Section 2: one inverter per wire, no address in the frame (the default range); not
        // streaming, the inverter only answers the master.
        .create_driver = &create_driver,
        .create_simulator = &create_simulator,
        .demo = demo_setup(kDemoOptions, 800),
    },
    kOptionSchema);

}  // namespace drivegate::nidec
