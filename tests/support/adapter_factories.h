// A driver or a simulator made by an adapter's own factory from options as text, as the gateway
// and `drivegate sim` make them, for the tests that call a driver or a simulator directly (no
// engine, no line). A factory that refuses fails the test with its own error and gives nothing.
// Tests of the factories' refusals call the descriptor's factories themselves.
//
//   auto d = test::make_driver(drivegate_adapter, {.options = {{"slave_mode", "true"}}});
//   auto sim = test::make_simulator(drivegate_adapter, 0x1F);
#pragma once

#include <cstdint>
#include <memory>

#include "bus_rig.h"
#include "drivegate/adapter.h"

namespace drivegate::test {

// What the gateway would hand the driver's factory (DeviceEnv), as text where it is options.
struct DriverSetup {
  OptionText options;  // over the schema's defaults
  std::uint32_t address = 0;
  Millis poll = DeviceEnv{}.poll_interval;
  bool maintenance = false;  // as `drivegate write` and `drivegate action` make it
};

std::unique_ptr<Driver> make_driver(const AdapterDescriptor& adapter,
                                    const DriverSetup& setup = {});
std::unique_ptr<Simulator> make_simulator(const AdapterDescriptor& adapter,
                                          std::uint32_t address = 0,
                                          const OptionText& options = {});

}  // namespace drivegate::test
