// Golden read plans: which requests read a profile's points.
#include "planner.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace drivegate::modbus_device {
namespace {

ProfilePoint point(std::string name, Table table, std::uint16_t address,
                   ValueType type = ValueType::u16) {
  ProfilePoint p;
  p.name = std::move(name);
  p.table = table;
  p.address = address;
  p.type = type;
  return p;
}

// The points of the example-vfd profile (adapters/modbus/profiles/example-vfd.toml).
Profile example(std::uint16_t max_gap = 4, std::uint16_t max_registers = 32) {
  Profile p;
  p.modbus.max_gap = max_gap;
  p.modbus.max_registers = max_registers;
  p.points = {point("status_word", Table::holding, 100),
              point("speed_actual", Table::input, 200, ValueType::s16),
              point("motor_current", Table::input, 202, ValueType::f32),
              point("fault_number", Table::input, 210),
              point("control_word", Table::holding, 0),
              point("speed_reference", Table::holding, 1, ValueType::s16)};
  return p;
}

TEST(Planner, TheExampleIsFourReads) {
  // Input: 200 and 202..203 are one register apart (joined: 200..203); 210 is six past 203, more
  // than max_gap 4. Holding: 0 and 1 adjoin; 100 is far.
  EXPECT_EQ(plan_reads(example()), (std::vector<Block>{{Table::input, 200, 4, {1, 2}},
                                                       {Table::input, 210, 1, {3}},
                                                       {Table::holding, 0, 2, {4, 5}},
                                                       {Table::holding, 100, 1, {0}}}));
}

TEST(Planner, AWiderGapJoinsTheInputsIntoOneRead) {
  EXPECT_EQ(plan_reads(example(6)), (std::vector<Block>{{Table::input, 200, 11, {1, 2, 3}},
                                                        {Table::holding, 0, 2, {4, 5}},
                                                        {Table::holding, 100, 1, {0}}}));
}

TEST(Planner, ABlockNeverExceedsTheDevicesLimit) {
  // max_registers 3: 200..203 is four registers, so the f32 starts a read of its own.
  EXPECT_EQ(plan_reads(example(6, 3)), (std::vector<Block>{{Table::input, 200, 1, {1}},
                                                           {Table::input, 202, 2, {2}},
                                                           {Table::input, 210, 1, {3}},
                                                           {Table::holding, 0, 2, {4, 5}},
                                                           {Table::holding, 100, 1, {0}}}));
}

TEST(Planner, NoGapMeansOnlyAdjacentPointsShareARead) {
  EXPECT_EQ(plan_reads(example(0)).size(), 5u);  // 200 | 202..203 | 210 | 0..1 | 100
}

TEST(Planner, ASubsetIsPlannedAloneAndFunctionsFollowTheTable) {
  const Profile p = example();
  const std::vector<std::size_t> some = {3, 1};
  EXPECT_EQ(plan_reads(p, some), (std::vector<Block>{{Table::input, 200, 1, {1}},
                                                     {Table::input, 210, 1, {3}}}));
  EXPECT_EQ(read_function(Table::coil), 0x01);
  EXPECT_EQ(read_function(Table::discrete), 0x02);
  EXPECT_EQ(read_function(Table::holding), 0x03);
  EXPECT_EQ(read_function(Table::input), 0x04);
}

TEST(Planner, BitsAreCountedInBitsUpToMaxBits) {
  Profile p;
  p.modbus.max_bits = 16;
  p.modbus.max_gap = 8;
  p.points = {point("a", Table::coil, 0, ValueType::bit), point("b", Table::coil, 9, ValueType::bit),
              point("c", Table::coil, 16, ValueType::bit)};
  // 0 and 9 (gap 8) join; 16 would make the read 17 bits long.
  EXPECT_EQ(plan_reads(p), (std::vector<Block>{{Table::coil, 0, 10, {0, 1}},
                                               {Table::coil, 16, 1, {2}}}));
}

}  // namespace
}  // namespace drivegate::modbus_device
