// The descriptor the plugin exports, with the facts of the document every adapter states
// (tests/support/descriptor_contract.h), the settings its options make, and the points of a
// device it creates.
#include <gtest/gtest.h>

#include <string>
#include <string_view>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "descriptor_contract.h"
#include "driver.h"
#include "points.h"
#include "settings.h"

namespace drivegate::nidec {
namespace {

using namespace std::chrono_literals;

using test::DescriptorContract;

// Section 3: 4800 baud, 8 bits, odd parity, one stop bit; section 2: one wire, no address.
// `drivegate demo`: a 7 kg washer at 800 rpm; no maintenance actions.
const test::DescriptorFacts kFacts{.id = "nidec-washer",
                                   .options = kOptionSchema,
                                   .line = {4800, Parity::odd, 8, 1, true},
                                   .demo_options = {{"platform", "7"}},
                                   .demo_rpm = 800};
INSTANTIATE_TEST_SUITE_P(Nidec, DescriptorContract, testing::Values(kFacts));

TEST(NidecPlugin, SettingsFromTheOptions) {
  const Settings defaults = test::settings_of(drivegate_adapter, parse_settings);
  EXPECT_EQ(defaults.platform, 7);
  EXPECT_EQ(defaults.empty_raw_weight, 0);
  EXPECT_EQ(defaults.accel_100ms, 30);
  EXPECT_EQ(defaults.attempts, 3);
  const Settings set = test::settings_of(drivegate_adapter, parse_settings,
                                         {{"platform", "8"},
                                          {"empty_raw_weight", "300"},
                                          {"accel_time_ms", "6553500"},
                                          {"attempts", "20"}});
  EXPECT_EQ(set.platform, 8);
  EXPECT_EQ(set.empty_raw_weight, 300);
  EXPECT_EQ(set.accel_100ms, 65535);
  EXPECT_EQ(set.attempts, 20);
  // 5.3: 100 ms units, rounded to the nearest.
  EXPECT_EQ(
      test::settings_of(drivegate_adapter, parse_settings, {{"accel_time_ms", "149"}}).accel_100ms,
      1);
  EXPECT_EQ(
      test::settings_of(drivegate_adapter, parse_settings, {{"accel_time_ms", "150"}}).accel_100ms,
      2);
  // The schema keeps out what a frame cannot carry.
  test::expect_schema_refuses(drivegate_adapter, {{"platform", "256"},
                                                  {"empty_raw_weight", "65536"},
                                                  {"accel_time_ms", "6553501"},
                                                  {"attempts", "0"}});
}

TEST(NidecPlugin, PointsAreAFixedTableWithLabels) {
  const auto d = test::make_driver(drivegate_adapter);
  ASSERT_NE(d, nullptr);
  const std::vector<PointSpec>& p = d->points();
  ASSERT_EQ(p.size(), pt::count);
  ASSERT_EQ(d->values().size(), pt::count);
  EXPECT_EQ(p[pt::motion].name, "motion");
  EXPECT_EQ(p[pt::motion].table, Table::holding);
  EXPECT_EQ(p[pt::motion].labels.size(), 4u);
  EXPECT_EQ(p[pt::motion].labels[3].name, "free_shaft_spin");
  EXPECT_EQ(p[pt::action].labels.size(), 8u);
  EXPECT_EQ(p[pt::action].labels[7].name, "ping");
  EXPECT_DOUBLE_EQ(p[pt::action].max, 7.0);
  EXPECT_EQ(p[pt::action_status].table, Table::input);
  EXPECT_TRUE(p[pt::error_bits].bit_labels);
  EXPECT_EQ(p[pt::error_bits].labels[3].name, "stall");
  EXPECT_EQ(p[pt::fabric_raw].register_count(), 2);
  EXPECT_DOUBLE_EQ(p[pt::accel_time].scale, 0.1);
  EXPECT_DOUBLE_EQ(p[pt::accel_time].max, 6553.5);       // 5.3: 16 bits of 100 ms
  EXPECT_DOUBLE_EQ(p[pt::agitation_ccw_off].max, 25.5);  // 5.5: one byte of 100 ms
  EXPECT_DOUBLE_EQ(p[pt::weight].scale, 0.1);
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_FALSE(p[i].description.empty()) << p[i].name;
    if (p[i].table == Table::holding) {
      EXPECT_LT(p[i].min, p[i].max) << p[i].name;
    }
  }
  // What a device starts with: the accel time of the options, the default agitation pattern.
  EXPECT_DOUBLE_EQ(as_double(d->values()[pt::accel_time]), 3.0);
  EXPECT_DOUBLE_EQ(as_double(d->values()[pt::agitation_cw_on]), 1.2);
  EXPECT_DOUBLE_EQ(as_double(d->values()[pt::agitation_ccw_off]), 0.8);
}

}  // namespace
}  // namespace drivegate::nidec
