// The mdriver-2400 plugin descriptor: option schema, line defaults and the two factories.
#include <array>
#include <memory>

#include "config.h"
#include "drivegate/adapter.h"
#include "driver.h"
#include "simulator.h"

namespace {

using drivegate::OptionSpec;
using drivegate::OptionType;

constexpr std::array<OptionSpec, 3> kOptions = {{
    // Section 3: master (PC) address [00].
    {drivegate::mdriver::kOptMasterAddress, OptionType::integer, "0",
     "the gateway's own address (D0 of every frame it sends)", 0, 255},
    // Section 3 No.2 / 連続運転モード: D5 = 0x01 (normal, 360 rpm/s) or 0xFF (continuous).
    {drivegate::mdriver::kOptMode, OptionType::string, "normal",
     "frequency change time D5: normal (0x01, 360 rpm/s) or continuous (0xFF)", 0, 0,
     "normal|continuous"},
    // Error table 0x0C: the driver stops after 6 s without a frame; 5 s leaves a margin.
    {drivegate::mdriver::kOptKeepalive, OptionType::integer, "1000",
     "longest gap between two run commands (the driver trips after 6 s)", 100, 5000},
}};

std::unique_ptr<drivegate::Driver> create_driver(const drivegate::DeviceEnv& env,
                                                 std::string& error) {
  const auto cfg = drivegate::mdriver::make_config(env.address, env.options, error);
  if (!cfg) return nullptr;
  return std::make_unique<drivegate::mdriver::MDriver>(*cfg, env.poll_interval);
}

std::unique_ptr<drivegate::Simulator> create_simulator(const drivegate::SimEnv& env,
                                                       std::string& error) {
  const auto cfg = drivegate::mdriver::make_config(env.address, env.options, error);
  if (!cfg) return nullptr;
  return std::make_unique<drivegate::mdriver::MSimulator>(cfg->device);
}

}  // namespace

extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
    drivegate::kAdapterApiVersion,
    "mdriver-2400",
    "compressor motor driver, sum-0x55 frames (Japanese spec)",
    kOptions.data(),
    kOptions.size(),
    // Section 1: 2400 bps, 8 data bits, no parity, 1 stop bit, full duplex (no echo).
    {2400, drivegate::Parity::none, 8, 1, false},
    0,  // Section 2: one-byte addresses
    255,
    0x01,  // Section 3: slave (driver) address [01]
    false,
    &create_driver,
    &create_simulator,
};
