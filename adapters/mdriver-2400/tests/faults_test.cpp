// The error code table (vendor document, モータドライバ エラーコード) and its unified faults.
#include "faults.h"

#include <gtest/gtest.h>

#include <utility>
#include <vector>

namespace drivegate::mdriver {
namespace {

TEST(MdriverErrors, IssueMappingOfEveryCode) {
  // Error table of the document, unified as the adapter's README assigns.
  const std::vector<std::pair<std::uint8_t, Fault>> expected = {
      {0x00, Fault::none},
      {0x01, Fault::over_voltage},
      {0x02, Fault::under_voltage},
      {0x03, Fault::over_current},
      {0x04, Fault::stall},
      {0x05, Fault::phase_loss},
      {0x06, Fault::phase_loss},
      {0x07, Fault::hardware_fault},
      {0x08, Fault::hardware_fault},
      {0x09, Fault::sensor_fault},
      {0x0A, Fault::other},
      {0x0B, Fault::hardware_fault},
      {0x0C, Fault::comm_lost},
      {0x0D, Fault::config_error},
      {0x0E, Fault::drive_over_temperature},
      {0x0F, Fault::other},
      {0xFF, Fault::other}};
  for (const auto& [code, fault] : expected) EXPECT_EQ(fault_of(code), fault) << int{code};
  EXPECT_EQ(error_codes().size(), 14u);
  EXPECT_EQ(find_error("ipm_over_temperature")->code, 0x0E);
}

TEST(MdriverErrors, LabelsNameEveryCode) {
  const auto labels = error_code_labels();
  ASSERT_EQ(labels.size(), 15u);
  EXPECT_EQ(labels[0].name, "none");
  EXPECT_EQ(labels[0].value, 0u);
  for (const auto& e : error_codes()) {
    EXPECT_EQ(labels.at(e.code).name, e.name);
    EXPECT_EQ(labels.at(e.code).value, e.code);
  }
}

}  // namespace
}  // namespace drivegate::mdriver
