// A plugin's descriptor made with describe() and demo_setup() (include/drivegate/adapter.h): each
// array's pointer and size from the array itself, the rest as the plugin wrote it.
#include "drivegate/adapter.h"

#include <gtest/gtest.h>

#include <array>

namespace drivegate {
namespace {

constexpr std::array<OptionSpec, 2> kSchema = {{
    {"speed", OptionType::integer, "10", "a speed", 0, 100},
    {"mode", OptionType::string, "a", "a mode", 0, 0, "a|b"},
}};
constexpr OptionSetting kDemo[] = {{"mode", "b"}};
constexpr MaintenanceAction kActions[] = {
    {"program", "programs it", "prog_", "prog_commit", "prog_message"},
    {"erase", "erases it", "erase_", "erase_commit", "erase_message"},
};

constexpr AdapterDescriptor kWithActions = describe(
    {
        .id = "x",
        .summary = "an adapter",
        .line = {9600, Parity::none, 8, 1, false},
        .address_max = 31,
        .demo = demo_setup(kDemo, 1234),
    },
    kSchema, kActions);
constexpr AdapterDescriptor kPlain = describe({.id = "y", .summary = "another"}, kSchema);

TEST(Describe, EachArrayGivesItsPointerAndSize) {
  EXPECT_EQ(kWithActions.options, kSchema.data());
  EXPECT_EQ(kWithActions.option_count, 2u);
  EXPECT_EQ(kWithActions.actions, kActions);
  EXPECT_EQ(kWithActions.action_count, 2u);
  EXPECT_EQ(kWithActions.demo.options, kDemo);
  EXPECT_EQ(kWithActions.demo.option_count, 1u);
  EXPECT_EQ(kWithActions.demo.running_rpm, 1234);
}

TEST(Describe, WhatThePluginWroteStaysAndTheRestIsTheDefaults) {
  EXPECT_EQ(kWithActions.api_version, kAdapterApiVersion);
  EXPECT_STREQ(kWithActions.id, "x");
  EXPECT_EQ(kWithActions.line.baud, 9600u);
  EXPECT_EQ(kWithActions.address_max, 31u);
  EXPECT_FALSE(kWithActions.streaming);
  EXPECT_EQ(kWithActions.specialise, nullptr);
  // No actions: none at all, not an empty array somewhere.
  EXPECT_EQ(kPlain.actions, nullptr);
  EXPECT_EQ(kPlain.action_count, 0u);
  EXPECT_EQ(kPlain.demo.options, nullptr);
  EXPECT_EQ(kPlain.demo.option_count, 0u);
  EXPECT_EQ(kPlain.demo.running_rpm, 1000);
  EXPECT_EQ(kPlain.option_count, 2u);
}

}  // namespace
}  // namespace drivegate
