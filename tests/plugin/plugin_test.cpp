// The plugin loader refuses what it cannot use, with a message naming the file, and loads the
// real adapters from the build tree.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>

#include "plugin/adapter_options.h"
#include "plugin/plugins.h"

namespace drivegate {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(Plugins, AnotherApiVersionIsRefusedClearly) {
  PluginRegistry r;
  const auto refused = r.load_directory(BAD_PLUGIN_DIR);
  ASSERT_EQ(refused.size(), 2u) << ::testing::PrintToString(refused);
  const auto all = ::testing::PrintToString(refused);
  EXPECT_THAT(
      all, AllOf(HasSubstr("drivegate-test-plugin-v999.so: adapter API version 999"),
                 HasSubstr("this drivegate speaks version " + std::to_string(kAdapterApiVersion))));
  EXPECT_THAT(all, HasSubstr("drivegate-test-plugin-nodesc.so: not a drivegate adapter"));
  EXPECT_EQ(r.find("from-the-future"), nullptr);
  EXPECT_EQ(r.ids(), "(none)");
}

TEST(Plugins, AnOptionDefaultOutsideItsRangeIsRefusedNamingPluginAndOption) {
  PluginRegistry r;
  const auto refused = r.load_directory(MIXED_PLUGIN_DIR);
  ASSERT_EQ(refused.size(), 1u) << ::testing::PrintToString(refused);
  EXPECT_THAT(refused[0], AllOf(HasSubstr("drivegate-test-plugin-baddefault.so: adapter "
                                          "'bad-default': option 'timeout_ms': default '5'"),
                                HasSubstr("must be in 10..1000")));
  EXPECT_EQ(r.find("bad-default"), nullptr);
  // The good plugin beside it still loads.
  EXPECT_EQ(r.ids(), "test-good");
}

TEST(Plugins, LinkedInDescriptorsAreCheckedLikePlugins) {
  const OptionSpec options[] = {
      {"count", OptionType::integer, "0x4", "an integer", 1, 10},
  };
  AdapterDescriptor d{
      kAdapterApiVersion,
      "linked",
      "linked in",
      options,
      std::size(options),
      {9600, Parity::none, 8, 1, false},
      0,
      0,
      0,
      false,
      [](const DeviceEnv&, std::string&) -> std::unique_ptr<Driver> { return nullptr; },
      [](const SimEnv&, std::string&) -> std::unique_ptr<Simulator> { return nullptr; }};
  PluginRegistry r;
  try {
    r.add(d);
    ADD_FAILURE() << "a descriptor with a bad default was added";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("adapter 'linked': option 'count': default '0x4'"),
                                HasSubstr("not a decimal integer")));
  }
  EXPECT_THROW(default_options(d), std::logic_error);

  const OptionSpec twice[] = {
      {"count", OptionType::integer, "4", "an integer", 1, 10},
      {"count", OptionType::integer, "5", "the same name", 1, 10},
  };
  d.options = twice;
  d.option_count = std::size(twice);
  EXPECT_THROW(r.add(d), std::invalid_argument);
  const OptionSpec undescribed[] = {{"count", OptionType::integer, "4", nullptr, 1, 10}};
  d.options = undescribed;
  d.option_count = 1;
  EXPECT_THROW(r.add(d), std::invalid_argument);
  const OptionSpec nameless[] = {{"", OptionType::integer, "4", "an integer", 1, 10}};
  d.options = nameless;
  EXPECT_THROW(r.add(d), std::invalid_argument);
  const OptionSpec no_default[] = {{"count", OptionType::integer, nullptr, "an integer", 1, 10}};
  d.options = no_default;
  EXPECT_THROW(r.add(d), std::invalid_argument);
  EXPECT_EQ(r.ids(), "(none)");

  const OptionSpec good[] = {{"count", OptionType::integer, "4", "an integer", 1, 10}};
  d.options = good;
  r.add(d);
  EXPECT_EQ(r.ids(), "linked");
  EXPECT_EQ(default_options(d).integer("count"), 4);
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
    // configuration sets no options at all. An adapter whose devices follow a description
    // (specialise) may be the exception when no default can say which (framed): the defaults are
    // then refused with an error naming the option, and its demo's options (which name one) make
    // both. One whose default names a description (modbus: the example profile) makes both.
    Options options = default_options(*d);
    std::string why;
    const AdapterDescriptor* device = d;
    if (d->specialise != nullptr) device = d->specialise(options, why);
    if (device == nullptr) {
      DeviceEnv bare;
      bare.name = "x";
      bare.options = options;
      EXPECT_EQ(d->create_driver(bare, why), nullptr) << d->id;
      EXPECT_THAT(why, HasSubstr("required")) << d->id;
      for (std::size_t i = 0; i < d->demo.option_count; ++i) {
        ASSERT_TRUE(
            set_option_text(*d, options, d->demo.options[i].name, d->demo.options[i].value, why))
            << d->id << ": " << why;
      }
      device = d->specialise(options, why);
      ASSERT_NE(device, nullptr) << d->id << ": " << why;
    }
    DeviceEnv env;
    env.name = "x";
    env.address = device->default_address;
    env.options = options;
    EXPECT_NE(d->create_driver(env, why), nullptr) << d->id << ": " << why;
    SimEnv sim{device->default_address, options};
    EXPECT_NE(d->create_simulator(sim, why), nullptr) << d->id << ": " << why;
  }
  EXPECT_GE(r.all().size(), 1u);
}

}  // namespace
}  // namespace drivegate
