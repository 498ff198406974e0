// The fdc1 plugin descriptor: option schema, line defaults, the two factories, how `drivegate
// demo` shows the controller, and the maintenance action `program`.
#include <memory>
#include <string>

#include "codec.h"
#include "drivegate/adapter.h"
#include "driver.h"
#include "points.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::fdc1 {
namespace {

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  const auto settings = parse_settings(env.options, error);
  if (!settings) return nullptr;
  // The programming points exist only where non-volatile memory may be written.
  return std::make_unique<Fdc1Driver>(*settings, env.maintenance || settings->allow_nv_programming);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  const auto settings = parse_settings(env.options, error);
  if (!settings) return nullptr;
  return std::make_unique<Fdc1Simulator>(*settings);
}

// `drivegate demo`: a controller in slave mode, the only one the gateway can run and stop.
constexpr OptionSetting kDemoOptions[] = {{"slave_mode", "true"}};

constexpr MaintenanceAction kActions[] = {{
    .name = kProgramAction,
    .summary = "programs the non-volatile settings (speeds, mode, battery cut-out / cut-in), "
               "validated against every limit of the document",
    .parameter_prefix = kProgramPrefix,
    .commit_point = kCommitPoint,
    .message_point = kMessagePoint,
}};

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
    {
        .id = "fdc1",
        .summary = "FDC1 12-42 V DC compressor controller, protocol v2 (streaming)",
        .line = kLine,
        // The protocol has no address (the default range): one controller per line.
        .streaming = true,  // OUTPUT: transmits every 0.5 s unasked
        .create_driver = &create_driver,
        .create_simulator = &create_simulator,
        // INPUT, Programming speed: 1500..3500 rpm; the specs README's example starts at 2000.
        .demo = demo_setup(kDemoOptions, 2000),
    },
    kOptionSchema, kActions);

}  // namespace drivegate::fdc1
