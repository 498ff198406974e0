// The descriptor the plugin exports, with the facts of the document every adapter states
// (tests/support/descriptor_contract.h: the address range too), and its factories' own rules.
#include <gtest/gtest.h>

#include <string>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "descriptor_contract.h"
#include "settings.h"

namespace drivegate::ed3100 {
namespace {

using test::DescriptorContract;

// The document offers 8N2, 8E1 and 8O1: 9600 8E1 is drivegate's default. Address 1..31 a drive,
// 0 the broadcast, 01 the factory setting. The drive only ever answers. `drivegate demo`: default
// options, 1500 rpm; no maintenance actions.
const test::DescriptorFacts kFacts{.id = "ed3100",
                                   .options = kOptionSchema,
                                   .line = {9600, Parity::even, 8, 1, false},
                                   .address_min = 0,
                                   .address_max = 31,
                                   .default_address = 1,
                                   .demo_rpm = 1500};
INSTANTIATE_TEST_SUITE_P(Ed3100, DescriptorContract, testing::Values(kFacts));

TEST(Ed3100Plugin, TheFactoriesUseTheOptions) {
  DeviceEnv env;
  env.address = 31;
  env.options = test::options_of(drivegate_adapter);
  std::string error;
  EXPECT_TRUE(drivegate_adapter.create_driver(env, error)) << error;
  env.options = test::options_of(drivegate_adapter, {{"poles", "5"}});
  EXPECT_FALSE(drivegate_adapter.create_driver(env, error));
  EXPECT_NE(error.find("poles"), std::string::npos);

  SimEnv sim{31, test::options_of(drivegate_adapter)};
  EXPECT_TRUE(drivegate_adapter.create_simulator(sim, error)) << error;
  sim.options = test::options_of(drivegate_adapter, {{"poles", "5"}});
  EXPECT_FALSE(drivegate_adapter.create_simulator(sim, error));
  EXPECT_NE(error.find("poles"), std::string::npos);
}

}  // namespace
}  // namespace drivegate::ed3100
