// Sparkplug topics (spec 4.1) and the primary host's STATE payload (spec 4.2.1, 3.0 form).
#include "mqtt/sparkplug.h"

#include <gtest/gtest.h>

namespace drivegate::sparkplug {
namespace {

TEST(SparkplugTopic, NodeAndDeviceTopicsHaveTheSpecsLevels) {
  EXPECT_EQ(topic("plant1", MessageType::nbirth, "gw01"), "spBv1.0/plant1/NBIRTH/gw01");
  EXPECT_EQ(topic("plant1", MessageType::ddata, "gw01", "washer-a"),
            "spBv1.0/plant1/DDATA/gw01/washer-a");
  EXPECT_EQ(topic("g", MessageType::ndeath, "n"), "spBv1.0/g/NDEATH/n");
}

TEST(SparkplugTopic, ParsesWhatItBuilds) {
  for (int t = 0; t < 8; ++t) {
    const auto type = static_cast<MessageType>(t);
    const bool device = type == MessageType::dbirth || type == MessageType::ddeath ||
                        type == MessageType::ddata || type == MessageType::dcmd;
    const auto parsed = parse_topic(topic("g1", type, "e1", device ? "d1" : ""));
    ASSERT_TRUE(parsed) << to_string(type);
    EXPECT_EQ(parsed->type, type);
    EXPECT_EQ(parsed->group, "g1");
    EXPECT_EQ(parsed->edge_node, "e1");
    EXPECT_EQ(parsed->device, device ? "d1" : "");
  }
}

TEST(SparkplugTopic, RefusesWhatIsNotOne) {
  for (const char* bad : {"", "spBv1.0", "spBv1.0/g/NBIRTH", "spAv1.0/g/NBIRTH/e",
                          "spBv1.0/g/NBIRTH/e/d",  // a node message with a device
                          "spBv1.0/g/DCMD/e",      // a device message without one
                          "spBv1.0/g/DCMD/e/d/x", "spBv1.0/g/NOPE/e", "spBv1.0//NCMD/e",
                          "spBv1.0/g/NCMD/", "spBv1.0/STATE/host", "spBv1.0/g/DCMD/e/+"}) {
    EXPECT_FALSE(parse_topic(bad)) << bad;
  }
}

TEST(SparkplugTopic, IdsMayNotHoldTopicSeparatorsOrWildcards) {
  EXPECT_TRUE(valid_id("washer-a"));
  EXPECT_TRUE(valid_id("Line 3.Fan"));
  for (const char* bad : {"", "a/b", "a+", "#"}) EXPECT_FALSE(valid_id(bad)) << bad;
}

TEST(SparkplugState, ReadsTheJsonOfSpec3) {
  EXPECT_EQ(state_topic("scada"), "spBv1.0/STATE/scada");
  auto s = parse_host_state(R"({"online" : true, "timestamp": 1700000000123})");
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->online);
  EXPECT_EQ(s->timestamp, 1700000000123u);
  s = parse_host_state("{\"timestamp\":5,\"online\":false}\n");
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->online);
  EXPECT_EQ(s->timestamp, 5u);
}

TEST(SparkplugState, RefusesAnythingElse) {
  for (const char* bad :
       {"", "ONLINE", "OFFLINE",  // Sparkplug 2.2's plain-text STATE
        "{}", R"({"online":true})", R"({"timestamp":1})", R"({"online":"true","timestamp":1})",
        R"({"online":true,"timestamp":-1})", R"({"online":true,"timestamp":1.5})",
        R"({"online":true,"timestamp":1} x)", R"({"online":true,"timestamp":1)",
        R"({"online":yes,"timestamp":1})", "[true, 1]"}) {
    EXPECT_FALSE(parse_host_state(bad)) << bad;
  }
}

TEST(SparkplugState, ReadsTheTextOf22WhereConfigured) {
  EXPECT_EQ(state_topic("scada", HostStateForm::v2_2), "STATE/scada");
  EXPECT_EQ(state_topic("scada", HostStateForm::v3_0), "spBv1.0/STATE/scada");
  auto s = parse_host_state("ONLINE", HostStateForm::v2_2);
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->online);
  EXPECT_EQ(s->timestamp, 0u);
  s = parse_host_state("OFFLINE", HostStateForm::v2_2);
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->online);
  for (const char* bad : {"", "online", "ONLINE\n", " ONLINE", "OFF", "ONLINEX",
                          R"({"online":true,"timestamp":1})"}) {
    EXPECT_FALSE(parse_host_state(bad, HostStateForm::v2_2)) << bad;
  }
}

TEST(SparkplugValue, FitsOnlyItsType) {
  EXPECT_TRUE(value_fits(DataType::int16, MetricValue{std::int64_t{-5}}));
  EXPECT_FALSE(value_fits(DataType::int16, MetricValue{std::uint64_t{5}}));
  EXPECT_TRUE(value_fits(DataType::uint64, MetricValue{std::uint64_t{5}}));
  EXPECT_TRUE(value_fits(DataType::boolean, MetricValue{true}));
  EXPECT_TRUE(value_fits(DataType::string, MetricValue{std::string("x")}));
  EXPECT_TRUE(value_fits(DataType::float32, MetricValue{}));  // null fits any
  EXPECT_FALSE(value_fits(DataType::float64, MetricValue{true}));
  EXPECT_EQ(number_of(MetricValue{true}), 1.0);
  EXPECT_EQ(number_of(MetricValue{std::string("1")}), std::nullopt);
}

}  // namespace
}  // namespace drivegate::sparkplug
