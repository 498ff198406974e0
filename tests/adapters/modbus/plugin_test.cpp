// The descriptor the plugin exports, with the facts every adapter states
// (tests/support/descriptor_contract.h), and its factories' own rules.
#include <gtest/gtest.h>

#include <string>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "descriptor_contract.h"
#include "settings.h"

namespace drivegate::modbus_device {
namespace {

using test::DescriptorContract;

// Serial Line 2.5.1: 19200 8E1 the default; 2.2: slaves 1..247. A slave only answers.
// `drivegate demo`: the example VFD at 1500 rpm; no maintenance actions.
const test::DescriptorFacts kFacts{.id = "modbus",
                                   .options = kOptionSchema,
                                   .line = {19200, Parity::even, 8, 1, false},
                                   .address_min = 1,
                                   .address_max = 247,
                                   .default_address = 1,
                                   .streaming = false,
                                   .demo_options = {{"profile", "example-vfd"}},
                                   .demo_rpm = 1500};
INSTANTIATE_TEST_SUITE_P(Modbus, DescriptorContract, testing::Values(kFacts));

TEST(ModbusPlugin, TheFactoriesReadTheProfileTheOptionsName) {
  DeviceEnv env;
  env.address = 247;
  env.options = test::options_of(drivegate_adapter);
  std::string error;
  EXPECT_TRUE(drivegate_adapter.create_driver(env, error)) << error;
  env.address = 0;  // the broadcast is never polled
  EXPECT_FALSE(drivegate_adapter.create_driver(env, error));
  EXPECT_NE(error.find("address 0"), std::string::npos) << error;
  env.address = 7;
  env.options = test::options_of(drivegate_adapter, {{"profile", "no-such-drive"}});
  EXPECT_FALSE(drivegate_adapter.create_driver(env, error));
  EXPECT_NE(error.find("option profile: no profile 'no-such-drive'"), std::string::npos) << error;

  SimEnv sim{7, test::options_of(drivegate_adapter)};
  EXPECT_TRUE(drivegate_adapter.create_simulator(sim, error)) << error;
  sim.address = 248;
  EXPECT_FALSE(drivegate_adapter.create_simulator(sim, error));
}

}  // namespace
}  // namespace drivegate::modbus_device
