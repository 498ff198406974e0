// The descriptor the plugin exports, with the facts of the document every adapter states
// (tests/support/descriptor_contract.h), and the settings the factories make of the options.
#include <gtest/gtest.h>

#include <string_view>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "descriptor_contract.h"
#include "settings.h"

namespace drivegate::mdriver {
namespace {

using test::DescriptorContract;

// Section 1: 2400 bps, 8N1, full duplex (no echo); one-byte addresses. `drivegate demo`: default
// options, running at 1149 rpm (code 0x40); no maintenance actions.
const test::DescriptorFacts kFacts{.id = "mdriver-2400",
                                   .options = kOptionSchema,
                                   .line = {2400, Parity::none, 8, 1, false},
                                   .address_min = 0,
                                   .address_max = 255,
                                   .default_address = 1,
                                   .demo_rpm = 1149};
INSTANTIATE_TEST_SUITE_P(Mdriver, DescriptorContract, testing::Values(kFacts));

TEST(MdriverPlugin, SettingsFromTheOptions) {
  const Settings defaults = test::settings_of(drivegate_adapter, parse_settings);
  EXPECT_EQ(defaults.master, 0x00);
  EXPECT_EQ(defaults.change, 0x01);
  EXPECT_EQ(defaults.keepalive, std::chrono::milliseconds(1000));
  const Settings set = test::settings_of(
      drivegate_adapter, parse_settings,
      {{"master_address", "16"}, {"mode", "continuous"}, {"keepalive_ms", "250"}});
  EXPECT_EQ(set.master, 0x10);
  EXPECT_EQ(set.change, 0xFF);
  EXPECT_EQ(set.keepalive, std::chrono::milliseconds(250));
  // The schema keeps what the protocol cannot carry out.
  test::expect_schema_refuses(
      drivegate_adapter, {{"keepalive_ms", "6000"}, {"mode", "fast"}, {"master_address", "256"}});
}

}  // namespace
}  // namespace drivegate::mdriver
