// The descriptor the plugin exports, as the loader, `drivegate demo`, `drivegate regmap` and
// `drivegate action` read it, and the settings the factories make of the options.
#include <gtest/gtest.h>

#include <string_view>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "points.h"
#include "settings.h"

namespace drivegate::fdc1 {
namespace {

TEST(Fdc1Plugin, Descriptor) {
  const AdapterDescriptor& a = drivegate_adapter;
  EXPECT_EQ(a.api_version, kAdapterApiVersion);
  EXPECT_EQ(std::string_view(a.id), "fdc1");
  // HARDWARE: 1200 baud, 8 data bits, no parity, 1 stop bit, separate RxD / TxD.
  EXPECT_EQ(a.line.baud, 1200u);
  EXPECT_EQ(a.line.parity, Parity::none);
  EXPECT_EQ(a.line.data_bits, 8);
  EXPECT_EQ(a.line.stop_bits, 1);
  EXPECT_FALSE(a.line.echo);
  // No address in the protocol; it streams, so it is alone on its line.
  EXPECT_EQ(a.address_min, 0u);
  EXPECT_EQ(a.address_max, 0u);
  EXPECT_TRUE(a.streaming);
  EXPECT_EQ(a.option_count, kOptionSchema.size());
}

TEST(Fdc1Plugin, DemoRunsASlaveModeControllerAt2000) {
  const DemoSetup& demo = drivegate_adapter.demo;
  ASSERT_EQ(demo.option_count, 1u);
  EXPECT_EQ(std::string_view(demo.options[0].name), "slave_mode");
  EXPECT_EQ(std::string_view(demo.options[0].value), "true");
  EXPECT_EQ(demo.running_rpm, 2000);
  // The demo's options parse against the schema, and the demo speed is one the driver takes.
  const Options o = test::options_of(drivegate_adapter, {{"slave_mode", "true"}});
  EXPECT_TRUE(o.boolean("slave_mode"));
  EXPECT_GE(demo.running_rpm, kMinRpm);
  EXPECT_LE(demo.running_rpm, kMaxRpm);
}

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
  std::string error;
  const auto defaults = parse_settings(test::options_of(drivegate_adapter), error);
  ASSERT_TRUE(defaults.has_value()) << error;
  EXPECT_FALSE(defaults->slave_mode);
  EXPECT_EQ(defaults->refresh, std::chrono::seconds(30));
  EXPECT_EQ(defaults->confirm, std::chrono::milliseconds(5000));
  EXPECT_EQ(defaults->stale, std::chrono::milliseconds(2000));
  EXPECT_EQ(defaults->tolerance_rpm, 100);
  EXPECT_FALSE(defaults->allow_nv_programming);
  const auto set =
      parse_settings(test::options_of(drivegate_adapter, {{"slave_mode", "true"},
                                                          {"refresh_s", "59"},
                                                          {"confirm_ms", "500"},
                                                          {"stale_ms", "60000"},
                                                          {"tolerance_rpm", "0"},
                                                          {"allow_nv_programming", "true"}}),
                     error);
  ASSERT_TRUE(set.has_value()) << error;
  EXPECT_TRUE(set->slave_mode);
  EXPECT_EQ(set->refresh, std::chrono::seconds(59));
  EXPECT_EQ(set->confirm, std::chrono::milliseconds(500));
  EXPECT_EQ(set->stale, std::chrono::milliseconds(60000));
  EXPECT_EQ(set->tolerance_rpm, 0);
  EXPECT_TRUE(set->allow_nv_programming);
  // The schema keeps what the controller cannot live with: a refresh past its 60 s watchdog, a
  // confirmation shorter than one stream period.
  EXPECT_THROW(test::options_of(drivegate_adapter, {{"refresh_s", "60"}}), std::invalid_argument);
  EXPECT_THROW(test::options_of(drivegate_adapter, {{"confirm_ms", "499"}}), std::invalid_argument);
  EXPECT_THROW(test::options_of(drivegate_adapter, {{"stale_ms", "999"}}), std::invalid_argument);
}

TEST(Fdc1Plugin, FactoriesMakeTheDriverAndTheSimulator) {
  std::string error;
  DeviceEnv env;
  env.options = test::options_of(drivegate_adapter);
  const auto plain = drivegate_adapter.create_driver(env, error);
  ASSERT_NE(plain, nullptr) << error;
  EXPECT_EQ(plain->points().size(), pt::prog_min_rpm);
  env.maintenance = true;
  const auto maintenance = drivegate_adapter.create_driver(env, error);
  ASSERT_NE(maintenance, nullptr) << error;
  EXPECT_EQ(maintenance->points().size(), pt::count);
  SimEnv senv;
  senv.options = env.options;
  EXPECT_NE(drivegate_adapter.create_simulator(senv, error), nullptr) << error;
}

}  // namespace
}  // namespace drivegate::fdc1
