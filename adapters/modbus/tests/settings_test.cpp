// Finding a profile by name or path, and what the options make of it.
#include "settings.h"

#include <gtest/gtest.h>

#include <fstream>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "profile_support.h"

namespace drivegate::modbus_device {
namespace {

TEST(ModbusSettings, TheShippedExampleIsFoundByName) {
  std::string error;
  const auto found = find_profile("example-vfd", error);
  ASSERT_TRUE(found) << error;
  // /etc/drivegate/profiles or /usr/share/drivegate/profiles first, where installed.
  if (found->source == "shipped example-vfd") {
    EXPECT_NE(found->text.find("name = \"example-vfd\""), std::string::npos);
  }
}

TEST(ModbusSettings, APathIsReadAndItsErrorsNameItsLines) {
  const support::ProfileFile bad(
      "[profile]\nname = \"bad\"\nsource = \"m\"\n[[point]]\nname = \"a\"\n"
      "table = \"input\"\naddress = 1\ntype = \"u16\"\n[common]\n"
      "running = { point = \"a\", bit = 16 }\nspeed_rpm = \"b\"\n",
      "bad.toml");
  const std::string& file = bad.path;
  std::string error;
  const auto s = parse_settings(test::options_of(drivegate_adapter, {{"profile", file}}), error);
  EXPECT_FALSE(s);
  // Every error, each with the file and its line, in file order, in one line.
  EXPECT_NE(error.find("option profile: " + file +
                       ":10: common.running.bit: must be in "
                       "0..15 (got 16); " +
                       file +
                       ":11: common.speed_rpm: no point is "
                       "called 'b'"),
            std::string::npos)
      << error;
  EXPECT_EQ(error.find('\n'), std::string::npos);
}

// The driver says which profile it read and a fingerprint of its text (Driver::files_read): the
// same text gives the same words, an edit other words, so that a reload sees the edit.
TEST(ModbusSettings, TheDriverSaysWhichProfileItReadAndItsContent) {
  std::string error;
  const auto shipped = find_profile("example-vfd", error);
  ASSERT_TRUE(shipped) << error;
  const support::ProfileFile vfd(shipped->text, "vfd.toml");
  const std::string& file = vfd.path;
  const auto driver_of = [&] {
    DeviceEnv env;
    env.address = 1;
    env.options = test::options_of(drivegate_adapter, {{"profile", file}});
    std::string why;
    auto d = drivegate_adapter.create_driver(env, why);
    EXPECT_TRUE(d) << why;
    return d ? d->files_read() : std::string();
  };
  const std::string first = driver_of();
  EXPECT_EQ(first.rfind("profile " + file + " (content ", 0), 0u) << first;
  EXPECT_EQ(driver_of(), first);  // read again, unchanged: the same
  std::ofstream(file) << shipped->text << "\n# an edit that changes nothing else\n";
  const std::string edited = driver_of();
  EXPECT_NE(edited, first);
  EXPECT_EQ(edited.rfind("profile " + file + " (content ", 0), 0u) << edited;
  // A pass-through device reads no file.
  DeviceEnv pass;
  pass.address = 1;
  pass.options = test::options_of(drivegate_adapter, {{"passthrough", "true"}});
  std::string why;
  auto p = drivegate_adapter.create_driver(pass, why);
  ASSERT_TRUE(p) << why;
  EXPECT_EQ(p->files_read(), "");
}

TEST(ModbusSettings, NamesThatAreNotNamesAndFilesThatAreNotFilesAreRefused) {
  std::string error;
  EXPECT_FALSE(find_profile("../etc/passwd", error));  // a path: read as one, if it is there
  EXPECT_FALSE(find_profile("Example VFD", error));
  EXPECT_NE(error.find("neither a profile name"), std::string::npos) << error;
  EXPECT_FALSE(find_profile("/dev", error));
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  EXPECT_FALSE(find_profile("/no/such/file.toml", error));
  EXPECT_NE(error.find("no profile file"), std::string::npos) << error;
}

TEST(ModbusSettings, TheOptionsReachTheSettings) {
  std::string error;
  const auto s = parse_settings(
      test::options_of(drivegate_adapter, {{"attempts", "5"}, {"comm_timeout_ms", "9000"}}), error);
  ASSERT_TRUE(s) << error;
  EXPECT_EQ(s->attempts, 5);
  EXPECT_EQ(s->comm_timeout, Millis(9000));
  EXPECT_EQ(s->profile.name, "example-vfd");
}

}  // namespace
}  // namespace drivegate::modbus_device
