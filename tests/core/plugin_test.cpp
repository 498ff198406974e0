// The plugin loader refuses what it cannot use, with a message naming the file, and loads the
// real adapters from the build tree.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "config/adapter_options.h"
#include "config/plugins.h"

namespace drivegate {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(Plugins, AnotherApiVersionIsRefusedClearly) {
  PluginRegistry r;
  const auto refused = r.load_directory(BAD_PLUGIN_DIR);
  ASSERT_EQ(refused.size(), 2u) << ::testing::PrintToString(refused);
  const auto all = ::testing::PrintToString(refused);
  EXPECT_THAT(all, AllOf(HasSubstr("drivegate-test-plugin-v999.so: adapter API version 999"),
                         HasSubstr("this drivegate speaks version 1")));
  EXPECT_THAT(all, HasSubstr("drivegate-test-plugin-nodesc.so: not a drivegate adapter"));
  EXPECT_EQ(r.find("from-the-future"), nullptr);
  EXPECT_EQ(r.ids(), "(none)");
}

TEST(Plugins, MissingDirectoryIsReported) {
  PluginRegistry r;
  const auto refused = r.load_directory("/nonexistent/plugins");
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_THAT(refused[0], HasSubstr("/nonexistent/plugins"));
}

TEST(Plugins, BuiltAdaptersLoadWithCompleteDescriptors) {
  PluginRegistry r;
  EXPECT_TRUE(r.load_directory(BUILD_PLUGIN_DIR).empty());
  for (const auto* d : r.all()) {
    EXPECT_EQ(d->api_version, kAdapterApiVersion);
    EXPECT_NE(d->create_driver, nullptr) << d->id;
    EXPECT_NE(d->create_simulator, nullptr) << d->id;
    EXPECT_GT(d->line.baud, 0u) << d->id;
    // Every default in the schema must make a device and a simulator: a newcomer's first
    // configuration sets no options at all.
    DeviceEnv env;
    env.name = "x";
    env.address = d->default_address;
    env.options = default_options(*d);
    std::string why;
    EXPECT_NE(d->create_driver(env, why), nullptr) << d->id << ": " << why;
    SimEnv sim{d->default_address, default_options(*d)};
    EXPECT_NE(d->create_simulator(sim, why), nullptr) << d->id << ": " << why;
  }
  EXPECT_GE(r.all().size(), 1u);
}

}  // namespace
}  // namespace drivegate
