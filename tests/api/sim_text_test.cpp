// The simulators' command and state-line text (include/drivegate/sim_text.h).
#include "drivegate/sim_text.h"

#include <gtest/gtest.h>

namespace drivegate {
namespace {

TEST(SimText, HexShowsTheDigitsAskedAndTheCaseAsked) {
  EXPECT_EQ(hex(0x2A, 4), "0x002A");
  EXPECT_EQ(hex(0x1C, 2, HexCase::lower), "0x1c");
  EXPECT_EQ(hex(0xABCDEF, 6), "0xABCDEF");
  EXPECT_EQ(hex(0x12345, 4), "0x12345");  // never cut
  EXPECT_EQ(hex(0xFFFFFFFFu, 8), "0xFFFFFFFF");
}

TEST(SimText, ANumberWithinTheTypeOrNothing) {
  EXPECT_EQ(parse_uint<std::uint8_t>("255"), 255);
  EXPECT_EQ(parse_uint<std::uint8_t>("0xff"), 255);
  EXPECT_FALSE(parse_uint<std::uint8_t>("256").has_value());
  EXPECT_EQ(parse_uint<std::uint16_t>("0xFFFF"), 0xFFFF);
  EXPECT_FALSE(parse_uint<std::uint16_t>("65536").has_value());
  for (const char* bad : {"", "-1", "0x", "1 ", "12a", "0x1g", "+1"}) {
    EXPECT_FALSE(parse_uint<std::uint16_t>(bad).has_value()) << bad;
  }
}

TEST(SimText, OnOrOffAndNothingElse) {
  EXPECT_EQ(parse_on_off("on"), true);
  EXPECT_EQ(parse_on_off("off"), false);
  for (const char* bad : {"", "On", "ON", "1", "onn", "of", " on"}) {
    EXPECT_FALSE(parse_on_off(bad).has_value()) << bad;
  }
}

}  // namespace
}  // namespace drivegate
