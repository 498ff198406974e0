// The framed plugin descriptor: one option of its own, `protocol`, and the specialiser that gives
// each described device the descriptor of its description (specialise.h); the two factories read
// the same description.
#include <memory>
#include <string>

#include "drivegate/adapter.h"
#include "driver.h"
#include "settings.h"
#include "simulator.h"
#include "specialise.h"

namespace drivegate::framed {

extern "C" DRIVEGATE_EXPORT const AdapterDescriptor drivegate_adapter;

namespace {

// The description the options name, for a device at `address`: nullptr and `error` when there
// is none or the address is outside its range (the core checks a configuration's; a tool's too).
std::shared_ptr<const Description> description_for(const Options& options, std::uint32_t address,
                                                   std::string& error) {
  auto d = load_description(options.has("protocol") ? options.string("protocol") : "", error);
  if (!d) return nullptr;
  if (address < d->address_min || address > d->address_max) {
    error = "address " + std::to_string(address) + " is outside " + d->name + "'s " +
            std::to_string(d->address_min) + ".." + std::to_string(d->address_max);
    return nullptr;
  }
  return d;
}

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error) {
  auto d = description_for(env.options, env.address, error);
  if (!d) return nullptr;
  return std::make_unique<FramedDriver>(std::move(d), env);
}

std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error) {
  auto d = description_for(env.options, env.address, error);
  if (!d) return nullptr;
  return std::make_unique<FramedSimulator>(std::move(d), env);
}

const AdapterDescriptor* specialise_device(const Options& options, std::string& error) {
  return specialise(drivegate_adapter, options, error);
}

// `drivegate demo`: the washer, described.
constexpr OptionSetting kDemoOptions[] = {{"protocol", "nidec-washer"}};

}  // namespace

extern "C" DRIVEGATE_EXPORT constinit const AdapterDescriptor drivegate_adapter = describe(
    {
        .id = "framed",
        .summary = "any serial protocol described in a TOML file (docs/protocols.md)",
        // The description's line, addresses and streaming come with its specialised descriptor;
        // these are only what a device with no usable description would be shown with.
        .line = {9600, Parity::none, 8, 1, false},
        .create_driver = &create_driver,
        .create_simulator = &create_simulator,
        .demo = demo_setup(kDemoOptions, 800),
        .specialise = &specialise_device,
    },
    kOptionSchema);

}  // namespace drivegate::framed
