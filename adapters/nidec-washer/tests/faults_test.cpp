// The section 8 fault table: the Error bitmask to the unified faults, and its labels.
#include "faults.h"

#include <gtest/gtest.h>

#include <utility>

namespace drivegate::nidec {
namespace {

TEST(NidecFaults, BitmaskMapping_section8) {
  EXPECT_TRUE(map_faults(0).empty());
  const std::pair<std::uint8_t, Fault> table[] = {
      {0x01, Fault::internal_error}, {0x02, Fault::drive_over_temperature},
      {0x04, Fault::over_voltage},   {0x08, Fault::stall},
      {0x10, Fault::over_current},   {0x20, Fault::under_voltage},
      {0x40, Fault::phase_loss},     {0x80, Fault::motor_over_temperature}};
  for (const auto& [bit, fault] : table) {
    const FaultSet s = map_faults(bit);
    EXPECT_EQ(s.bits(), 1u << static_cast<unsigned>(fault)) << int{bit};
  }
  // Several bits at once (section 8: a bitmask).
  const FaultSet all = map_faults(0xFF);
  for (const auto& [bit, fault] : table) EXPECT_TRUE(all.has(fault)) << int{bit};
  EXPECT_EQ(most_severe(map_faults(0x18)), Fault::over_current);
}

TEST(NidecFaults, LabelsNameTheBitsAndTheSimulatorsFaults) {
  const std::vector<Label> labels = fault_bit_labels();
  ASSERT_EQ(labels.size(), 8u);
  EXPECT_EQ(labels[0].name, "general");
  EXPECT_EQ(labels[3].name, "stall");
  EXPECT_EQ(labels[3].value, 3u);  // bit 3 = 0x08
  EXPECT_EQ(labels[7].name, "motor_over_temperature");
  for (const Label& l : labels) EXPECT_EQ(fault_mask(l.name), 1u << l.value) << l.name;
  EXPECT_EQ(fault_mask("nonsense"), std::nullopt);
  EXPECT_EQ(fault_names().rfind("general|ipm_over_temperature|", 0), 0u);
}

}  // namespace
}  // namespace drivegate::nidec
