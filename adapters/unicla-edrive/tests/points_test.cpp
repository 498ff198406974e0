// The points the "Running Limits/ RS485 Config" reply fills: each range's low and high land on the
// points of that range's name, in the units the point table declares.
#include "points.h"

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

namespace drivegate::unicla {
namespace {

TEST(UniclaPoints, EachRunningLimitFillsThePointOfItsName) {
  // Speeds, the six ranges in the struct's (and the reply's) order, device id, control enabled.
  const RunningLimits l{1500,
                        6000,
                        {1.0F, 6.0F},
                        {8.0F, 28.0F},
                        {-30.0F, 20.0F},
                        {10.0F, 120.0F},
                        {3.0F, 15.0F},
                        {12.0F, 45.0F},
                        7,
                        1};
  const std::vector<PointSpec> points = make_points();
  std::vector<Value> v(points.size());
  fill_running_limits(v, l);
  const auto read = [&](const std::string& name) {
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (points[i].name == name) return as_double(v[i]);
    }
    ADD_FAILURE() << "no point " << name;
    return -1.0;
  };
  const std::pair<std::string, double> expected[] = {
      {"limit_min_speed", 1500},
      {"limit_max_speed", 6000},
      {"suction_pressure_low", 1},
      {"suction_pressure_high", 6},
      {"discharge_pressure_low", 8},
      {"discharge_pressure_high", 28},
      {"suction_temperature_low", -30},
      {"suction_temperature_high", 20},
      {"discharge_temperature_low", 10},
      {"discharge_temperature_high", 120},
      {"suction_superheat_low", 3},
      {"suction_superheat_high", 15},
      {"discharge_superheat_low", 12},
      {"discharge_superheat_high", 45},
      {"rs485_device_id", 7},
      {"control_enabled", 1},
  };
  for (const auto& [name, value] : expected) {
    SCOPED_TRACE(name);
    EXPECT_DOUBLE_EQ(read(name), value);
  }
}

}  // namespace
}  // namespace drivegate::unicla
