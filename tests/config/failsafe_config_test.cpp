// The failsafe keys of a [[device]]: off and stop by default, every action accepted, and every
// bad value refused with the file, line and key named.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "config/config_loader.h"
#include "fake_adapter.h"

namespace drivegate {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

class FailsafeConfigTest : public ::testing::Test {
 protected:
  FailsafeConfigTest() { plugins_.add(test::kFakeAdapter); }
  // A one-device file with `keys` added to the [[device]] table (line 7 on).
  ConfigResult parse(const std::string& keys) {
    return parse_config(
        "[[bus]]\nname = \"l\"\nport = \"/dev/null\"\n[[device]]\nname = \"d\"\n"
        "bus = \"l\"\nadapter = \"fake\"\nunit_id = 1\n" +
            keys,
        "gw.toml", plugins_);
  }
  std::string only_error(const std::string& keys) {
    auto r = parse(keys);
    EXPECT_FALSE(r.config.has_value());
    EXPECT_EQ(r.errors.size(), 1u) << ::testing::PrintToString(r.errors);
    return r.errors.empty() ? "" : r.errors.front();
  }
  PluginRegistry plugins_;
};

TEST_F(FailsafeConfigTest, OffAndStopByDefault) {
  const auto r = parse("");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const auto& d = r.config->devices.at(0);
  EXPECT_EQ(d.failsafe.timeout, Millis(0));
  EXPECT_EQ(d.failsafe.action, FailsafeAction::stop);
  EXPECT_EQ(d.on_shutdown, ShutdownAction::stop);
  EXPECT_EQ(d.on_start, StartAction::adopt);
}

TEST_F(FailsafeConfigTest, ReadsEveryKey) {
  auto r = parse(
      "failsafe_timeout_ms = 1500\nfailsafe_action = \"preset\"\nfailsafe_rpm = 300\n"
      "on_shutdown = \"hold\"\non_start = \"stop\"\n");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const auto& d = r.config->devices.at(0);
  EXPECT_EQ(d.failsafe.timeout, Millis(1500));
  EXPECT_EQ(d.failsafe.action, FailsafeAction::preset);
  EXPECT_EQ(d.failsafe.preset_rpm, 300);
  EXPECT_EQ(d.on_shutdown, ShutdownAction::hold);
  EXPECT_EQ(d.on_start, StartAction::stop);
  for (const auto& [text, action] : {std::pair{"stop", FailsafeAction::stop},
                                     std::pair{"quick_stop", FailsafeAction::quick_stop},
                                     std::pair{"hold", FailsafeAction::hold}}) {
    r = parse(std::string("failsafe_action = \"") + text + "\"\n");
    ASSERT_TRUE(r.config) << text;
    EXPECT_EQ(r.config->devices.at(0).failsafe.action, action);
  }
}

TEST_F(FailsafeConfigTest, RefusesBadValues) {
  EXPECT_THAT(only_error("failsafe_timeout_ms = 50\n"),
              AllOf(HasSubstr("gw.toml:9"), HasSubstr("device[0].failsafe_timeout_ms"),
                    HasSubstr("0 (off) or 100..3600000")));
  EXPECT_THAT(only_error("failsafe_timeout_ms = -1\n"), HasSubstr("failsafe_timeout_ms"));
  EXPECT_THAT(only_error("failsafe_action = \"brake\"\n"),
              AllOf(HasSubstr("gw.toml:9"), HasSubstr("stop, quick_stop, hold or preset")));
  EXPECT_THAT(only_error("failsafe_action = \"preset\"\n"),
              AllOf(HasSubstr("device[0].failsafe_rpm"), HasSubstr("required")));
  EXPECT_THAT(only_error("failsafe_action = \"preset\"\nfailsafe_rpm = 40000\n"),
              HasSubstr("failsafe_rpm"));
  EXPECT_THAT(only_error("failsafe_rpm = 300\n"),
              AllOf(HasSubstr("gw.toml:9"), HasSubstr("only used with failsafe_action")));
  EXPECT_THAT(only_error("on_shutdown = \"coast\"\n"),
              AllOf(HasSubstr("device[0].on_shutdown"), HasSubstr("stop or hold")));
  EXPECT_THAT(only_error("on_start = \"run\"\n"),
              AllOf(HasSubstr("gw.toml:9"), HasSubstr("device[0].on_start"),
                    HasSubstr("adopt or stop")));
}

}  // namespace
}  // namespace drivegate
