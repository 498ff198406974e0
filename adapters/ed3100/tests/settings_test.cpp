// The options as the gateway hands them over (text over the schema's defaults), and the point
// table they make.
#include "settings.h"

#include <gtest/gtest.h>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "descriptor_contract.h"
#include "points.h"

namespace drivegate::ed3100 {
namespace {

Settings settings(const test::OptionText& text) {
  return test::settings_of(drivegate_adapter, parse_settings, text);
}

TEST(Ed3100Settings, ParametersAreTheirAddress) {
  // Document, "Setting parameters GGnnH": 04-01 is 0x0401.
  EXPECT_EQ(parse_parameter("04-01"), 0x0401);
  EXPECT_EQ(parse_parameter("00-06"), 0x0006);
  EXPECT_EQ(parse_parameter("0c-1f"), 0x0C1F);
  EXPECT_FALSE(parse_parameter("0D-00"));  // the monitor block
  EXPECT_FALSE(parse_parameter("4-01"));
  EXPECT_FALSE(parse_parameter("04_01"));
}

TEST(Ed3100Settings, Monitors) {
  EXPECT_EQ(parse_monitor("0D00")->reg, 0x0D00);
  EXPECT_EQ(parse_monitor("0d28:A")->unit, "A");
  EXPECT_FALSE(parse_monitor("0D29"));  // document: "reading invalid address more than 0D28"
  EXPECT_FALSE(parse_monitor("0D01:W"));
}

TEST(Ed3100Settings, TheDefaultsMakeADevice) {
  const Settings s = settings({});
  EXPECT_EQ(s.poles, 4);
  ASSERT_EQ(s.monitors.size(), 4u);
  EXPECT_EQ(s.speed_monitor, 0u);
  EXPECT_EQ(s.monitors[0].unit, "Hz");
  EXPECT_TRUE(s.parameters.empty());
  EXPECT_EQ(s.frame_gap, Millis(10));
  EXPECT_EQ(s.timeout, Millis(100));
  EXPECT_EQ(s.attempts, 3);
  EXPECT_EQ(s.comm_timeout, Millis(3000));
  EXPECT_EQ(s.reset_register, 0x2002);
  EXPECT_EQ(s.reset_value, 0x0002);
  EXPECT_EQ(s.sim_reply_form, ReadForm::document);
  std::string error;
  EXPECT_EQ(device_address(31, error), 31);
  EXPECT_EQ(device_address(0, error), 0);  // the broadcast
}

TEST(Ed3100Settings, TheSpeedMonitorIsAddedWhenNotListed) {
  const Settings s = settings({{"monitors", "0D02:V"}});
  ASSERT_EQ(s.monitors.size(), 2u);
  EXPECT_EQ(s.monitors[s.speed_monitor].reg, 0x0D00);
  EXPECT_EQ(s.monitors[s.speed_monitor].unit, "Hz");
}

TEST(Ed3100Settings, OptionsThatDoNotMakeADeviceAreNamed) {
  std::string error;
  EXPECT_FALSE(device_address(32, error));
  EXPECT_NE(error.find("address"), std::string::npos);
  test::expect_settings_refuse(drivegate_adapter, parse_settings,
                               {{"poles", "3"},
                                {"parameters", "00-06,00-06"},
                                {"parameters", "0D-00"},
                                {"monitors", "0E01"},
                                {"monitors", "0D01,0d01:A"},
                                {"speed_monitor", "0D29"}});
}

TEST(Ed3100Points, TableLayout) {
  const Settings s = settings({{"parameters", "00-06,0A-01"}});
  const auto pts = make_points(s);
  ASSERT_EQ(pts.size(), pt::count + 3 * 4 + 2);
  EXPECT_EQ(pts[pt::drive_fault_code].name, "drive_fault_code");
  EXPECT_EQ(pts[pt::state_word].bit_labels, true);
  EXPECT_EQ(pts[pt::decelerating].name, "decelerating");
  EXPECT_EQ(pts[pt::frequency_setpoint].name, "frequency_setpoint");
  EXPECT_EQ(pts[pt::frequency_setpoint].table, Table::holding);
  EXPECT_EQ(pts[pt::frequency_setpoint].scale, 0.01);
  EXPECT_EQ(pts[pt::frequency_setpoint].max, 655.35);
  EXPECT_EQ(pts[pt::monitor_value(0)].name, "monitor_0d00");
  EXPECT_EQ(pts[pt::monitor_value(0)].type, PointType::f32);
  EXPECT_EQ(pts[pt::monitor_value(0)].unit, "Hz");
  EXPECT_EQ(pts[pt::monitor_raw(0)].name, "monitor_0d00_raw");
  EXPECT_EQ(pts[pt::monitor_format(3)].name, "monitor_0d03_format");
  EXPECT_EQ(pts[pt::parameter(s, 0)].name, "param_00_06");
  EXPECT_EQ(pts[pt::parameter(s, 1)].name, "param_0a_01");
  EXPECT_EQ(pts[pt::parameter(s, 1)].table, Table::holding);
  EXPECT_EQ(pts[pt::parameter(s, 1)].max, 65535);
}

}  // namespace
}  // namespace drivegate::ed3100
