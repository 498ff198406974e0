// What `drivegate dcmd` makes of its METRIC=VALUE arguments, and how it knows the DDATA that
// answers its command (cli/dcmd_metrics.h): the types the edge node takes, labels by name, and
// only its own result.
#include "dcmd_metrics.h"

#include <gtest/gtest.h>

#include "mqtt/edge_node.h"

namespace drivegate::cli {
namespace {

using sparkplug::DataType;
using sparkplug::Metric;

PointSpec command_point() {
  PointSpec p{.name = "command", .table = Table::holding, .type = PointType::u16};
  p.labels = {{"stop", 0}, {"run_forward", 1}, {"run_reverse", 2}};
  return p;
}

TEST(DcmdMetrics, NumbersBooleansAndLabelsTakeTheTypesTheEdgeNodeReads) {
  std::string error;
  const PointSpec cmd = command_point();
  const auto run = command_metric({"command", "run_forward"}, &cmd, error);
  ASSERT_TRUE(run) << error;
  EXPECT_EQ(run->name, "command");
  EXPECT_EQ(run->type, DataType::int64);
  EXPECT_EQ(run->value, sparkplug::MetricValue{std::int64_t{1}});
  const auto whole = command_metric({"setpoint_rpm", "-600"}, nullptr, error);
  ASSERT_TRUE(whole);
  EXPECT_EQ(whole->type, DataType::int64);
  EXPECT_EQ(whole->value, sparkplug::MetricValue{std::int64_t{-600}});
  const auto real = command_metric({"accel_time", "1.5"}, nullptr, error);
  ASSERT_TRUE(real);
  EXPECT_EQ(real->type, DataType::float64);
  EXPECT_EQ(real->value, sparkplug::MetricValue{1.5});
  const auto yes = command_metric({"enable", "true"}, nullptr, error);
  ASSERT_TRUE(yes);
  EXPECT_EQ(yes->type, DataType::boolean);
  EXPECT_EQ(yes->value, sparkplug::MetricValue{true});
  // A number wins over a label of the same spelling, as `drivegate write` reads them.
  EXPECT_EQ(command_metric({"command", "2"}, &cmd, error)->value,
            sparkplug::MetricValue{std::int64_t{2}});
}

TEST(DcmdMetrics, WhatIsNoValueIsSaidBeforeAnythingIsSent) {
  const PointSpec cmd = command_point();
  for (const char* bad : {"sideways", "", "nan", "inf", "1e999", "+5", "0x10", "True"}) {
    std::string error;
    EXPECT_FALSE(command_metric({"command", bad}, &cmd, error)) << bad;
    EXPECT_EQ(error, "command: '" + std::string(bad) +
                         "' is not a number, true or false or a label of the point")
        << bad;
  }
  std::string error;
  EXPECT_FALSE(command_metric({"speed", "fast"}, nullptr, error));
  EXPECT_EQ(error, "speed: 'fast' is not a number, true or false");
}

sparkplug::Payload ddata(std::string points, std::string result) {
  sparkplug::Payload p;
  p.metrics.push_back({.name = std::string(sparkplug::kCommandPoint),
                       .type = DataType::string,
                       .value = std::move(points)});
  p.metrics.push_back({.name = std::string(sparkplug::kCommandResult),
                       .type = DataType::string,
                       .value = std::move(result)});
  return p;
}

TEST(DcmdMetrics, OnlyTheDdataNamingThisCommandsMetricsIsItsResult) {
  EXPECT_EQ(result_of(ddata("setpoint_rpm,command", "ok"), "setpoint_rpm,command"), "ok");
  EXPECT_EQ(result_of(ddata("command", "exception 0x04 (server device failure)"), "command"),
            "exception 0x04 (server device failure)");
  EXPECT_FALSE(result_of(ddata("command,setpoint_rpm", "ok"), "setpoint_rpm,command"));
  EXPECT_FALSE(result_of(ddata("command", "ok"), "setpoint_rpm,command"));
  sparkplug::Payload speed;  // a DDATA of values alone
  speed.metrics.push_back({.name = "speed_rpm", .type = DataType::int16, .value = std::int64_t{5}});
  EXPECT_FALSE(result_of(speed, "command"));
}

}  // namespace
}  // namespace drivegate::cli
