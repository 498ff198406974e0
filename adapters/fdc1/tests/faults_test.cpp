// OUTPUT, "Alarm codes": ranges of 16 named by their first value (specs README, fdc1), the unified
// faults they stand for, and the alarm_code point's labels.
#include "faults.h"

#include <gtest/gtest.h>

namespace drivegate::fdc1 {
namespace {

TEST(Fdc1Faults, RangesMapToUnifiedFaults) {
  struct Case {
    int first;
    Fault fault;
    bool latched;
  };
  const Case cases[] = {
      {16, Fault::supply_fault, false},
      {32, Fault::fan_fault, false},
      {48, Fault::stall, false},
      {64, Fault::overload, false},
      {80, Fault::drive_over_temperature, false},
      {160, Fault::fan_fault, true},
      {176, Fault::stall, true},
      {192, Fault::overload, true},
      {208, Fault::drive_over_temperature, true},
      {240, Fault::internal_error, false},
  };
  for (const auto& c : cases) {
    for (const int code : {c.first, c.first + 7, c.first + 15}) {
      SCOPED_TRACE(code);
      const Alarm a = classify_alarm(static_cast<std::uint8_t>(code));
      EXPECT_EQ(a.fault, c.fault);
      EXPECT_EQ(a.latched, c.latched);
    }
  }
}

TEST(Fdc1Faults, ZeroIsNoAlarmAndGapsAreOther) {
  EXPECT_EQ(classify_alarm(0).fault, Fault::none);
  for (const int code : {1, 15, 96, 144, 159, 224, 239}) {
    SCOPED_TRACE(code);
    EXPECT_EQ(classify_alarm(static_cast<std::uint8_t>(code)).fault, Fault::other);
    EXPECT_FALSE(classify_alarm(static_cast<std::uint8_t>(code)).latched);
  }
}

TEST(Fdc1Faults, LabelsNameTheFirstCodeOfEachRange) {
  const std::vector<Label> labels = alarm_labels();
  ASSERT_EQ(labels.size(), 11u);
  EXPECT_EQ(labels[0].name, "none");
  EXPECT_EQ(labels[0].value, 0u);
  EXPECT_EQ(labels[3].name, "motor failed to start");
  EXPECT_EQ(labels[3].value, 48u);
  EXPECT_EQ(labels[10].name, "internal error");
  EXPECT_EQ(labels[10].value, 240u);
}

TEST(Fdc1Faults, TheSimulatorsNamesFindTheirRange) {
  ASSERT_TRUE(find_alarm("start_eor").has_value());
  EXPECT_EQ(find_alarm("start_eor")->first, 176);
  EXPECT_EQ(find_alarm("battery")->fault, Fault::supply_fault);
  EXPECT_FALSE(find_alarm("nonsense").has_value());
}

}  // namespace
}  // namespace drivegate::fdc1
