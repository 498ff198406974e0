// The descriptor the plugin exports, with the facts of the document every adapter states
// (tests/support/descriptor_contract.h), its maintenance action, and the settings the factories
// make of the options.
#include <gtest/gtest.h>

#include <string_view>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "descriptor_contract.h"
#include "points.h"
#include "settings.h"

namespace drivegate::fdc1 {
namespace {

using test::DescriptorContract;

// HARDWARE: 1200 baud, 8 data bits, no parity, 1 stop bit, separate RxD / TxD. No address in the
// protocol; it streams, so it is alone on its line. `drivegate demo`: a slave-mode controller at
// 2000 rpm (INPUT, Programming speed: 1500..3500; the specs README's example range starts at
// 2000). One maintenance action, `program`.
const test::DescriptorFacts kFacts{.id = "fdc1",
                                   .options = kOptionSchema,
                                   .line = {1200, Parity::none, 8, 1, false},
                                   .streaming = true,
                                   .demo_options = {{"slave_mode", "true"}},
                                   .demo_rpm = 2000,
                                   .action_count = 1};
INSTANTIATE_TEST_SUITE_P(Fdc1, DescriptorContract, testing::Values(kFacts));

TEST(Fdc1Plugin, OneMaintenanceActionProgram) {
  ASSERT_EQ(drivegate_adapter.action_count, 1u);
  const MaintenanceAction& a = drivegate_adapter.actions[0];
  EXPECT_EQ(std::string_view(a.name), "program");
  EXPECT_EQ(std::string_view(a.parameter_prefix), "prog_");
  EXPECT_EQ(std::string_view(a.commit_point), "prog_commit");
  EXPECT_EQ(std::string_view(a.message_point), "prog_message");
  EXPECT_NE(std::string_view(a.summary).find("validated against every limit"),
            std::string_view::npos);
}

TEST(Fdc1Plugin, SettingsFromTheOptions) {
  const Settings defaults = test::settings_of(drivegate_adapter, parse_settings);
  EXPECT_FALSE(defaults.slave_mode);
  EXPECT_EQ(defaults.refresh, std::chrono::seconds(30));
  EXPECT_EQ(defaults.confirm, std::chrono::milliseconds(5000));
  EXPECT_EQ(defaults.stale, std::chrono::milliseconds(2000));
  EXPECT_EQ(defaults.tolerance_rpm, 100);
  EXPECT_FALSE(defaults.allow_nv_programming);
  const Settings set = test::settings_of(drivegate_adapter, parse_settings,
                                         {{"slave_mode", "true"},
                                          {"refresh_s", "59"},
                                          {"confirm_ms", "500"},
                                          {"stale_ms", "60000"},
                                          {"tolerance_rpm", "0"},
                                          {"allow_nv_programming", "true"}});
  EXPECT_TRUE(set.slave_mode);
  EXPECT_EQ(set.refresh, std::chrono::seconds(59));
  EXPECT_EQ(set.confirm, std::chrono::milliseconds(500));
  EXPECT_EQ(set.stale, std::chrono::milliseconds(60000));
  EXPECT_EQ(set.tolerance_rpm, 0);
  EXPECT_TRUE(set.allow_nv_programming);
  // The schema keeps what the controller cannot live with: a refresh past its 60 s watchdog, a
  // confirmation shorter than one stream period.
  test::expect_schema_refuses(drivegate_adapter,
                              {{"refresh_s", "60"}, {"confirm_ms", "499"}, {"stale_ms", "999"}});
}

// The programming points exist only in maintenance mode (or by option: program_action_test.cpp).
TEST(Fdc1Plugin, MaintenanceModeAddsTheProgrammingPoints) {
  const auto plain = test::make_driver(drivegate_adapter);
  ASSERT_NE(plain, nullptr);
  EXPECT_EQ(plain->points().size(), pt::prog_min_rpm);
  const auto maintenance = test::make_driver(drivegate_adapter, {.maintenance = true});
  ASSERT_NE(maintenance, nullptr);
  EXPECT_EQ(maintenance->points().size(), pt::count);
}

}  // namespace
}  // namespace drivegate::fdc1
