// [mqtt]: the broker's address forms, Sparkplug ids, report-by-exception limits, command policy
// and secrets; every mistake named with the file, line and key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "config/config_loader.h"
#include "fake_adapter.h"

namespace drivegate {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr const char* kDevice = R"(
[[bus]]
name = "line1"
port = "/dev/ttyUSB0"

[[device]]
name = "washer-a"
bus = "line1"
adapter = "fake"
unit_id = 1
)";

class MqttConfigTest : public ::testing::Test {
 protected:
  MqttConfigTest() { plugins_.add(test::kFakeAdapter); }
  ConfigResult parse(const std::string& mqtt, const std::string& device = kDevice) {
    return parse_config(device + "\n" + mqtt, "gw.toml", plugins_);
  }
  std::string only_error(const std::string& mqtt, const std::string& device = kDevice) {
    auto r = parse(mqtt, device);
    EXPECT_FALSE(r.config.has_value());
    EXPECT_EQ(r.errors.size(), 1u) << ::testing::PrintToString(r.errors);
    return r.errors.empty() ? "" : r.errors.front();
  }
  PluginRegistry plugins_;
};

TEST_F(MqttConfigTest, OffUnlessPresent) {
  const auto r = parse("");
  ASSERT_TRUE(r.config);
  EXPECT_FALSE(r.config->mqtt.enabled);
}

TEST_F(MqttConfigTest, TheIssuesExampleLoads) {
  const auto r = parse(R"(
[mqtt]
broker = "mqtt://127.0.0.1:1883"
client_id = "drivegate-gw01"
group_id = "plant1"
edge_node_id = "gw01"
deadband = { speed_rpm = 5 }
min_interval_ms = 100
commands = false
)");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const MqttConfig& m = r.config->mqtt;
  EXPECT_TRUE(m.enabled);
  EXPECT_EQ(m.host, "127.0.0.1");
  EXPECT_EQ(m.port, 1883);
  EXPECT_FALSE(m.tls);
  EXPECT_EQ(m.group_id, "plant1");
  EXPECT_EQ(m.edge_node_id, "gw01");
  EXPECT_EQ(m.client_id, "drivegate-gw01");
  ASSERT_EQ(m.deadband.size(), 1u);
  EXPECT_EQ(m.deadband[0], (std::pair<std::string, double>{"speed_rpm", 5.0}));
  EXPECT_EQ(m.min_interval, Millis(100));
  EXPECT_EQ(m.counter_interval, Millis(10'000));
  EXPECT_FALSE(m.commands);
  EXPECT_EQ(m.access, AccessLevel::operate);
  EXPECT_FALSE(m.feed_failsafe);
  EXPECT_THAT(::testing::PrintToString(r.warnings), Not(HasSubstr("mqtt")));
}

TEST_F(MqttConfigTest, BrokerForms) {
  auto r =
      parse("[mqtt]\nbroker = \"mqtt://broker.plant\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n");
  ASSERT_TRUE(r.config);
  EXPECT_EQ(r.config->mqtt.host, "broker.plant");
  EXPECT_EQ(r.config->mqtt.port, 1883);
  EXPECT_EQ(r.config->mqtt.client_id, "drivegate-e");
  r = parse("[mqtt]\nbroker = \"mqtt://[::1]:2883\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n");
  ASSERT_TRUE(r.config);
  EXPECT_EQ(r.config->mqtt.host, "::1");
  EXPECT_EQ(r.config->mqtt.port, 2883);
  for (const char* bad : {"tcp://h:1883", "mqtt://", "mqtt://h:0", "mqtt://h:65536",
                          "mqtt://h:", "mqtt://h:x", "mqtt://[::1", "mqtt://h/path", "h:1883"}) {
    EXPECT_THAT(only_error(std::string("[mqtt]\nbroker = \"") + bad +
                           "\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n"),
                AllOf(HasSubstr("gw.toml:"), HasSubstr("mqtt.broker"), HasSubstr("mqtt://")))
        << bad;
  }
}

TEST_F(MqttConfigTest, IdsAreRequiredAndMustBeSparkplugIds) {
  EXPECT_THAT(only_error("[mqtt]\nbroker = \"mqtt://h\"\nedge_node_id = \"e\"\n"),
              AllOf(HasSubstr("mqtt.group_id"), HasSubstr("missing")));
  EXPECT_THAT(
      only_error("[mqtt]\nbroker = \"mqtt://h\"\ngroup_id = \"a/b\"\nedge_node_id = \"e\"\n"),
      AllOf(HasSubstr("gw.toml:14"), HasSubstr("mqtt.group_id"), HasSubstr("'/'")));
  EXPECT_THAT(
      only_error("[mqtt]\nbroker = \"mqtt://h\"\ngroup_id = \"g\"\nedge_node_id = \"e#\"\n"),
      HasSubstr("mqtt.edge_node_id"));
}

// Device names are published as Sparkplug device ids: the configuration's name rule keeps the
// characters Sparkplug reserves out of them, with [mqtt] or without.
TEST_F(MqttConfigTest, DeviceNamesAreValidDeviceIds) {
  std::string device = kDevice;
  device.replace(device.find("washer-a"), 8, "washer+a");
  EXPECT_THAT(
      only_error("[mqtt]\nbroker = \"mqtt://h\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n", device),
      AllOf(HasSubstr("gw.toml:7"), HasSubstr("device[0].name"), HasSubstr("letters, digits")));
  EXPECT_FALSE(parse("", device).config);
}

TEST_F(MqttConfigTest, LimitsAndPolicyAreChecked) {
  const std::string head =
      "[mqtt]\nbroker = \"mqtt://h\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n";
  EXPECT_THAT(only_error(head + "deadband = { speed_rpm = -1 }\n"),
              AllOf(HasSubstr("mqtt.deadband.speed_rpm"), HasSubstr(">= 0")));
  EXPECT_THAT(only_error(head + "deadband = 5\n"), HasSubstr("mqtt.deadband"));
  EXPECT_THAT(only_error(head + "min_interval_ms = -1\n"), HasSubstr("mqtt.min_interval_ms"));
  EXPECT_THAT(only_error(head + "keepalive_s = 1\n"), HasSubstr("mqtt.keepalive_s"));
  EXPECT_THAT(only_error(head + "access = \"all\"\n"), HasSubstr("mqtt.access"));
  EXPECT_THAT(only_error(head + "qos = 1\n"),
              AllOf(HasSubstr("mqtt.qos"), HasSubstr("unknown key")));
  const auto r = parse(head + "commands = true\naccess = \"maintain\"\nfeed_failsafe = true\n");
  ASSERT_TRUE(r.config);
  EXPECT_TRUE(r.config->mqtt.commands);
  EXPECT_EQ(r.config->mqtt.access, AccessLevel::maintain);
  EXPECT_TRUE(r.config->mqtt.feed_failsafe);
  // Commands over plain MQTT: valid, and warned about.
  EXPECT_THAT(::testing::PrintToString(r.warnings), HasSubstr("mqtts://"));
  EXPECT_THAT(::testing::PrintToString(parse(head + "feed_failsafe = true\n").warnings),
              HasSubstr("no effect"));
}

TEST_F(MqttConfigTest, TlsNeedsACaAndClientCertificatesComeInPairs) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("dg-mqtt-tls-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string ca = (dir / "ca.pem").string();
  std::ofstream(ca) << "-----BEGIN CERTIFICATE-----\n";
  const std::string ids = "group_id = \"g\"\nedge_node_id = \"e\"\n";
  EXPECT_THAT(only_error("[mqtt]\nbroker = \"mqtts://h\"\n" + ids), HasSubstr("mqtt.ca"));
  EXPECT_THAT(only_error("[mqtt]\nbroker = \"mqtt://h\"\nca = \"" + ca + "\"\n" + ids),
              HasSubstr("mqtts://"));
  EXPECT_THAT(
      only_error("[mqtt]\nbroker = \"mqtts://h\"\nca = \"" + ca + "\"\ncert = \"/c\"\n" + ids),
      HasSubstr("cert and key"));
  const auto r = parse("[mqtt]\nbroker = \"mqtts://h\"\nca = \"" + ca + "\"\n" + ids);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_TRUE(r.config->mqtt.tls);
  EXPECT_EQ(r.config->mqtt.port, 8883);
  // libmosquitto reads the files by path on the event loop: a FIFO is refused here, saying so.
  const auto fifo = dir / "ca.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THAT(
      only_error("[mqtt]\nbroker = \"mqtts://h\"\nca = \"" + fifo.string() + "\"\n" + ids),
      AllOf(HasSubstr("mqtt.ca"), HasSubstr("a FIFO, not a regular file")));
  std::filesystem::remove_all(dir);
}

TEST_F(MqttConfigTest, PasswordFileMustBePrivate) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("dg-mqtt-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = dir / "password";
  std::ofstream(file) << "s3cret\nignored\n";
  const std::string head =
      "[mqtt]\nbroker = \"mqtt://h\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n";
  ::chmod(file.c_str(), 0600);
  auto r = parse(head + "username = \"gw\"\npassword_file = \"" + file.string() + "\"\n");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_EQ(r.config->mqtt.password, "s3cret");
  ::chmod(file.c_str(), 0644);
  EXPECT_THAT(only_error(head + "username = \"gw\"\npassword_file = \"" + file.string() + "\"\n"),
              AllOf(HasSubstr("mqtt.password_file"), HasSubstr("readable by others")));
  EXPECT_THAT(only_error(head + "password_file = \"" + file.string() + "\"\n"),
              HasSubstr("needs a username"));
  EXPECT_THAT(
      only_error(head + "username = \"gw\"\npassword_file = \"" + (dir / "none").string() + "\"\n"),
      HasSubstr("cannot read"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace drivegate
