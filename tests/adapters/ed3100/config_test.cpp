#include "config.h"

#include <gtest/gtest.h>

#include "points.h"
#include "schema.h"
#include "test_options.h"

namespace drivegate::ed3100 {
namespace {

TEST(Ed3100Config, ParsesParametersAsTheirAddress) {
  // Document, "Setting parameters GGnnH": 04-01 is 0x0401.
  EXPECT_EQ(parse_parameter("04-01"), 0x0401);
  EXPECT_EQ(parse_parameter("00-06"), 0x0006);
  EXPECT_EQ(parse_parameter("0c-1f"), 0x0C1F);
  EXPECT_FALSE(parse_parameter("0D-00"));  // the monitor block
  EXPECT_FALSE(parse_parameter("4-01"));
  EXPECT_FALSE(parse_parameter("04_01"));
}

TEST(Ed3100Config, ParsesMonitors) {
  EXPECT_EQ(parse_monitor("0D00")->reg, 0x0D00);
  EXPECT_EQ(parse_monitor("0d28:A")->unit, "A");
  EXPECT_FALSE(parse_monitor("0D29"));  // document: "reading invalid address more than 0D28"
  EXPECT_FALSE(parse_monitor("0D01:W"));
}

TEST(Ed3100Config, DefaultsMakeADevice) {
  std::string error;
  const auto c = make_config(31, test::options(), error);
  ASSERT_TRUE(c) << error;
  EXPECT_EQ(c->address, 31);
  EXPECT_EQ(c->monitors.size(), 4u);
  EXPECT_EQ(c->speed_monitor, 0u);
  EXPECT_EQ(c->monitors[0].unit, "Hz");
}

TEST(Ed3100Config, SpeedMonitorIsAddedWhenNotListed) {
  std::string error;
  const auto c =
      make_config(1, test::options({{"monitors", std::vector<std::string>{"0D02:V"}}}), error);
  ASSERT_TRUE(c) << error;
  ASSERT_EQ(c->monitors.size(), 2u);
  EXPECT_EQ(c->monitors[c->speed_monitor].reg, 0x0D00);
}

TEST(Ed3100Config, RejectsBadOptions) {
  std::string error;
  EXPECT_FALSE(make_config(32, test::options(), error));
  EXPECT_NE(error.find("address"), std::string::npos);
  EXPECT_FALSE(make_config(1, test::options({{"poles", std::int64_t{3}}}), error));
  EXPECT_NE(error.find("poles"), std::string::npos);
  EXPECT_FALSE(make_config(
      1, test::options({{"parameters", std::vector<std::string>{"00-06", "00-06"}}}), error));
  EXPECT_NE(error.find("parameters"), std::string::npos);
  EXPECT_FALSE(
      make_config(1, test::options({{"monitors", std::vector<std::string>{"0E01"}}}), error));
  EXPECT_NE(error.find("monitors"), std::string::npos);
}

TEST(Ed3100Points, TableLayout) {
  std::string error;
  const auto c = make_config(
      1, test::options({{"parameters", std::vector<std::string>{"00-06", "0A-01"}}}), error);
  ASSERT_TRUE(c);
  const auto pts = make_points(*c);
  ASSERT_EQ(pts.size(), kFixedCount + 3 * 4 + 2);
  EXPECT_EQ(pts[index(Fixed::fault_code)].name, "fault_code");
  EXPECT_EQ(pts[monitor_value_index(0)].name, "monitor_0d00");
  EXPECT_EQ(pts[monitor_value_index(0)].unit, "Hz");
  EXPECT_EQ(pts[monitor_value_index(0) + 1].name, "monitor_0d00_raw");
  EXPECT_EQ(pts[monitor_value_index(0) + 2].name, "monitor_0d00_format");
  EXPECT_EQ(pts[parameter_index(*c, 0)].name, "param_00_06");
  EXPECT_EQ(pts[parameter_index(*c, 1)].name, "param_0a_01");
  EXPECT_EQ(pts[parameter_index(*c, 1)].table, Table::holding);
  EXPECT_EQ(pts[parameter_index(*c, 1)].max, 65535);
}

TEST(Ed3100Schema, FactoriesUseTheOptions) {
  DeviceEnv env;
  env.address = 31;
  env.options = test::options();
  std::string error;
  EXPECT_TRUE(create_driver(env, error)) << error;
  env.address = 40;
  EXPECT_FALSE(create_driver(env, error));
  SimEnv sim{31, test::options()};
  EXPECT_TRUE(create_simulator(sim, error));
  for (const auto& o : kOptionSpecs) EXPECT_TRUE(test::options().has(o.name)) << o.name;
}

}  // namespace
}  // namespace drivegate::ed3100
