// The descriptor the plugin exports, as the loader, `drivegate demo` and `drivegate regmap` read
// it.
#include <gtest/gtest.h>

#include <string_view>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "settings.h"

namespace drivegate::mdriver {
namespace {

TEST(MdriverPlugin, Descriptor) {
  const AdapterDescriptor& a = drivegate_adapter;
  EXPECT_EQ(a.api_version, kAdapterApiVersion);
  EXPECT_EQ(std::string_view(a.id), "mdriver-2400");
  // Section 1: 2400 bps, 8N1, full duplex (no echo).
  EXPECT_EQ(a.line.baud, 2400u);
  EXPECT_EQ(a.line.parity, Parity::none);
  EXPECT_EQ(a.line.data_bits, 8);
  EXPECT_EQ(a.line.stop_bits, 1);
  EXPECT_FALSE(a.line.echo);
  EXPECT_EQ(a.address_min, 0u);
  EXPECT_EQ(a.address_max, 255u);
  EXPECT_EQ(a.default_address, 1u);
  EXPECT_FALSE(a.streaming);
  EXPECT_EQ(a.option_count, kOptionSchema.size());
  // `drivegate demo`: default options, running at 1149 rpm (code 0x40); no maintenance actions.
  EXPECT_EQ(a.demo.option_count, 0u);
  EXPECT_EQ(a.demo.running_rpm, 1149);
  EXPECT_EQ(a.action_count, 0u);
  EXPECT_EQ(a.actions, nullptr);
}

TEST(MdriverPlugin, SettingsFromTheOptions) {
  std::string error;
  const auto defaults = parse_settings(test::options_of(drivegate_adapter), error);
  ASSERT_TRUE(defaults.has_value()) << error;
  EXPECT_EQ(defaults->master, 0x00);
  EXPECT_EQ(defaults->change, 0x01);
  EXPECT_EQ(defaults->keepalive, std::chrono::milliseconds(1000));
  const auto set = parse_settings(
      test::options_of(drivegate_adapter,
                       {{"master_address", "16"}, {"mode", "continuous"}, {"keepalive_ms", "250"}}),
      error);
  ASSERT_TRUE(set.has_value()) << error;
  EXPECT_EQ(set->master, 0x10);
  EXPECT_EQ(set->change, 0xFF);
  EXPECT_EQ(set->keepalive, std::chrono::milliseconds(250));
  // The schema keeps what the protocol cannot carry out.
  EXPECT_THROW(test::options_of(drivegate_adapter, {{"keepalive_ms", "6000"}}),
               std::invalid_argument);
  EXPECT_THROW(test::options_of(drivegate_adapter, {{"mode", "fast"}}), std::invalid_argument);
  EXPECT_THROW(test::options_of(drivegate_adapter, {{"master_address", "256"}}),
               std::invalid_argument);
}

}  // namespace
}  // namespace drivegate::mdriver
