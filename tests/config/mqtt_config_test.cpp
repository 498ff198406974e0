// [mqtt]: the broker's address forms, Sparkplug ids, report-by-exception limits, command policy
// and secrets; every mistake named with the file, line and key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>

#include "config/config_loader.h"
#include "fake_adapter.h"

namespace drivegate::mqtt_config_test {
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
  ASSERT_EQ(m.brokers.size(), 1u);
  EXPECT_EQ(m.brokers[0].url, "mqtt://127.0.0.1:1883");
  EXPECT_EQ(m.brokers[0].host, "127.0.0.1");
  EXPECT_EQ(m.brokers[0].port, 1883);
  EXPECT_FALSE(m.brokers[0].tls);
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
  EXPECT_EQ(r.config->mqtt.brokers.at(0).host, "broker.plant");
  EXPECT_EQ(r.config->mqtt.brokers.at(0).port, 1883);
  EXPECT_EQ(r.config->mqtt.client_id, "drivegate-e");
  r = parse("[mqtt]\nbroker = \"mqtt://[::1]:2883\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n");
  ASSERT_TRUE(r.config);
  EXPECT_EQ(r.config->mqtt.brokers.at(0).host, "::1");
  EXPECT_EQ(r.config->mqtt.brokers.at(0).port, 2883);
  for (const char* bad : {"tcp://h:1883", "mqtt://", "mqtt://h:0", "mqtt://h:65536",
                          "mqtt://h:", "mqtt://h:x", "mqtt://[::1", "mqtt://h/path", "h:1883"}) {
    EXPECT_THAT(only_error(std::string("[mqtt]\nbroker = \"") + bad +
                           "\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n"),
                AllOf(HasSubstr("gw.toml:"), HasSubstr("mqtt.broker"), HasSubstr("mqtt://")))
        << bad;
  }
}

// A URL with credentials would never connect (the host would be "user:secret@h") and would show
// the password in the status JSON and the log: refused by the check, without quoting it.
TEST_F(MqttConfigTest, CredentialsInABrokerUrlAreRefusedWithoutShowingThem) {
  for (const char* bad : {"mqtt://gw01:s3cret@10.1.2.3:1883", "mqtts://gw01:s3cret@broker",
                          "mqtt://s3cret@[::1]:1883"}) {
    const std::string e = only_error(std::string("[mqtt]\nbroker = \"") + bad +
                                     "\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n");
    EXPECT_THAT(e, AllOf(HasSubstr("gw.toml:"), HasSubstr("mqtt.broker"),
                         HasSubstr("credentials in a broker URL"), HasSubstr("password_file")))
        << bad;
    EXPECT_THAT(e, Not(HasSubstr("s3cret"))) << bad;
  }
  const std::string e = only_error(
      "[mqtt]\nbrokers = [\"mqtt://a\", { url = \"mqtt://u:s3cret@b\" }]\ngroup_id = "
      "\"g\"\nedge_node_id = \"e\"\n");
  EXPECT_THAT(e, AllOf(HasSubstr("mqtt.brokers[1]"), Not(HasSubstr("s3cret"))));
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

// The primary host's STATE: 3.0's JSON unless the host is a Sparkplug 2.2 one.
TEST_F(MqttConfigTest, PrimaryHostVersionIs30Or22) {
  const std::string head =
      "[mqtt]\nbroker = \"mqtt://h\"\ngroup_id = \"g\"\nedge_node_id = \"e\"\n";
  auto r = parse(head + "primary_host_id = \"scada\"\n");
  ASSERT_TRUE(r.config);
  EXPECT_EQ(r.config->mqtt.primary_host_state, MqttHostState::v3_0);
  r = parse(head + "primary_host_id = \"scada\"\nprimary_host_version = \"2.2\"\n");
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_EQ(r.config->mqtt.primary_host_state, MqttHostState::v2_2);
  EXPECT_THAT(::testing::PrintToString(r.warnings), Not(HasSubstr("mqtt")));
  EXPECT_THAT(only_error(head + "primary_host_id = \"scada\"\nprimary_host_version = \"2\"\n"),
              AllOf(HasSubstr("gw.toml:17"), HasSubstr("mqtt.primary_host_version"),
                    HasSubstr("\"3.0\""), HasSubstr("\"2.2\"")));
  r = parse(head + "primary_host_version = \"2.2\"\n");
  ASSERT_TRUE(r.config);
  EXPECT_THAT(::testing::PrintToString(r.warnings),
              AllOf(HasSubstr("mqtt.primary_host_version"), HasSubstr("primary_host_id")));
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
  EXPECT_TRUE(r.config->mqtt.brokers.at(0).tls);
  EXPECT_EQ(r.config->mqtt.brokers.at(0).port, 8883);
  // libmosquitto reads the files by path on the event loop: a FIFO is refused here, saying so.
  const auto fifo = dir / "ca.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THAT(only_error("[mqtt]\nbroker = \"mqtts://h\"\nca = \"" + fifo.string() + "\"\n" + ids),
              AllOf(HasSubstr("mqtt.ca"), HasSubstr("a FIFO, not a regular file")));
  std::filesystem::remove_all(dir);
}

// brokers = [...]: tried in order; each mqtts:// one with [mqtt]'s TLS files unless it names its
// own (its own CA brings its own client pair, or none).
TEST_F(MqttConfigTest, SeveralBrokersInOrderEachWithItsTls) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("dg-mqtt-brokers-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = [&](const char* name) {
    const auto p = dir / name;
    std::ofstream(p) << "-----BEGIN-----\n";
    std::filesystem::permissions(
        p, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
    return p.string();
  };
  const std::string ca = file("ca.pem"), ca2 = file("ca2.pem"), cert = file("c.pem"),
                    key = file("k.pem"), cert2 = file("c2.pem"), key2 = file("k2.pem");
  const std::string ids = "group_id = \"g\"\nedge_node_id = \"e\"\n";
  auto r = parse(
      "[mqtt]\nbrokers = [\"mqtts://a\", \"mqtt://b:1884\", { url = \"mqtts://c:9000\", ca "
      "= \"" +
      ca2 + "\" }, { url = \"mqtts://d\", cert = \"" + cert2 + "\", key = \"" + key2 +
      "\" }]\nca = \"" + ca + "\"\ncert = \"" + cert + "\"\nkey = \"" + key + "\"\n" + ids);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  const auto& b = r.config->mqtt.brokers;
  ASSERT_EQ(b.size(), 4u);
  EXPECT_EQ(b[0].url, "mqtts://a");
  EXPECT_EQ(b[0].port, 8883);
  EXPECT_EQ(b[0].ca, ca);
  EXPECT_EQ(b[0].cert, cert);
  EXPECT_EQ(b[1].host, "b");
  EXPECT_EQ(b[1].port, 1884);
  EXPECT_FALSE(b[1].tls);
  EXPECT_EQ(b[1].ca, "");
  EXPECT_EQ(b[2].ca, ca2);
  EXPECT_EQ(b[2].cert, "") << "its own CA, no client pair of its own: none";
  EXPECT_EQ(b[3].ca, ca);
  EXPECT_EQ(b[3].cert, cert2);
  EXPECT_EQ(b[3].key, key2);

  // Mistakes, each named where it is.
  EXPECT_THAT(only_error("[mqtt]\nbroker = \"mqtt://a\"\nbrokers = [\"mqtt://b\"]\n" + ids),
              HasSubstr("broker or brokers, not both"));
  EXPECT_THAT(only_error("[mqtt]\n" + ids), AllOf(HasSubstr("mqtt.broker"), HasSubstr("missing")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = []\n" + ids),
              AllOf(HasSubstr("mqtt.brokers"), HasSubstr("1..8")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = [\"mqtt://a\", \"tcp://b\"]\n" + ids),
              AllOf(HasSubstr("gw.toml:13"), HasSubstr("mqtt.brokers[1]"), HasSubstr("mqtt://")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = [\"mqtt://a\", \"mqtts://b\"]\n" + ids),
              AllOf(HasSubstr("mqtt.brokers[1]"), HasSubstr("needs `ca`")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = [{ url = \"mqtt://a\", ca = \"" + ca + "\" }]\n" + ids),
              AllOf(HasSubstr("mqtt.brokers[0]"), HasSubstr("for an mqtts:// broker")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = [{ url = \"mqtt://a\", port = 1 }]\n" + ids),
              AllOf(HasSubstr("mqtt.brokers[0].port"), HasSubstr("unknown key")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = [{ ca = \"" + ca + "\" }]\n" + ids),
              AllOf(HasSubstr("mqtt.brokers[0].url"), HasSubstr("missing")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = [1]\n" + ids),
              AllOf(HasSubstr("mqtt.brokers[0]"), HasSubstr("broker URL or a table")));
  EXPECT_THAT(only_error("[mqtt]\nbrokers = [{ url = \"mqtts://a\", ca = \"" + dir.string() +
                         "/none.pem\" }]\n" + ids),
              HasSubstr("mqtt.brokers[0].ca"));
  std::string nine = "[mqtt]\nbrokers = [";
  for (int i = 0; i < 9; ++i)
    nine += std::string(i ? ", " : "") + "\"mqtt://h" + std::to_string(i) + "\"";
  EXPECT_THAT(only_error(nine + "]\n" + ids), HasSubstr("1..8"));
  // Commands over any plain broker are warned about.
  r = parse("[mqtt]\nbrokers = [\"mqtts://a\", \"mqtt://b\"]\nca = \"" + ca +
            "\"\ncommands = true\n" + ids);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  EXPECT_THAT(::testing::PrintToString(r.warnings), HasSubstr("mqtts://"));
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
}  // namespace drivegate::mqtt_config_test
