// validate_program, rule by rule (INPUT, "Programming mode + parameters": speeds 1500..3500 rpm,
// mode members, and "must fulfill the next requirements" for STANDARD and SPECIAL).
#include "program.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace drivegate::fdc1 {
namespace {

using ::testing::HasSubstr;

ProgramSettings standard() {
  ProgramSettings p;
  p.min_rpm = 2000;
  p.max_rpm = 3000;
  p.mode = kModeSlave;
  p.cut_out_12v = 10.5;
  p.cut_in_12v = 12.5;
  p.cut_out_24v = 21.0;
  p.cut_in_24v = 25.0;
  p.cut_out_42v = 36.0;
  p.cut_in_42v = 44.0;
  return p;
}

ProgramSettings special() {
  ProgramSettings p;
  p.min_rpm = 1800;
  p.max_rpm = 3200;
  p.mode = kModeSlave | kModeSpecial;
  p.cut_out_special = 10.0;
  p.cut_in_special = 11.6;
  p.nominal_voltage = 14.0;
  return p;
}

std::string why(const ProgramSettings& p) {
  const auto r = validate_program(p);
  return r ? *r : std::string("valid");
}

TEST(Fdc1Program, ValidSettingsPass) {
  EXPECT_EQ(validate_program(standard()), std::nullopt);
  EXPECT_EQ(validate_program(special()), std::nullopt);
}

TEST(Fdc1Program, SpeedsWithin1500And3500) {
  auto p = standard();
  p.min_rpm = 1499;
  EXPECT_THAT(why(p), HasSubstr("min_rpm 1499 rpm is outside 1500..3500"));
  p.min_rpm = 1500;
  p.max_rpm = 3501;
  EXPECT_THAT(why(p), HasSubstr("max_rpm 3501 rpm is outside"));
  p.max_rpm = 3500;
  EXPECT_EQ(why(p), "valid");  // both ends included
}

TEST(Fdc1Program, MinimumNotAboveMaximum) {
  auto p = standard();
  p.min_rpm = 3000;
  p.max_rpm = 2000;
  EXPECT_THAT(why(p), HasSubstr("above max_rpm"));
  p.max_rpm = 3000;
  EXPECT_EQ(why(p), "valid");
}

TEST(Fdc1Program, ModeMembers) {
  auto p = standard();
  for (const int m : {0, 2, 3, 4, 8, 12, 16, 128, 128 + 16 + 12 + 3}) {
    p.mode = static_cast<std::uint8_t>(m);
    EXPECT_EQ(why(p), "valid") << m;
  }
  p.mode = 1;
  EXPECT_THAT(why(p), HasSubstr("control member 1"));
  p.mode = 64;
  EXPECT_THAT(why(p), HasSubstr("64"));
  p = special();
  p.mode = kModeSpecial | kModeExternalLimits;
  EXPECT_THAT(why(p), HasSubstr("exclude each other"));
}

struct Rule {
  const char* name;
  void (*breaks)(ProgramSettings&);
  const char* says;
};

TEST(Fdc1Program, StandardRules) {
  const Rule rules[] = {
      {"cut_out_12v < cut_in_12v", [](ProgramSettings& p) { p.cut_out_12v = p.cut_in_12v; },
       "cut_out_12v 12.50 V must be below cut_in_12v 12.50 V"},
      {"cut_out_24v < cut_in_24v", [](ProgramSettings& p) { p.cut_in_24v = 20.0; },
       "cut_out_24v 21.00 V must be below cut_in_24v 20.00 V"},
      {"cut_out_42v < cut_in_42v", [](ProgramSettings& p) { p.cut_out_42v = 45.0; },
       "cut_out_42v 45.00 V must be below cut_in_42v 44.00 V"},
      {"cut_out_12v > 9V", [](ProgramSettings& p) { p.cut_out_12v = 9.0; },
       "cut_out_12v 9.00 V must be above 9 V"},
      {"cut_in_12v < 17V", [](ProgramSettings& p) { p.cut_in_12v = 17.0; },
       "cut_in_12v 17.00 V must be below 17 V"},
      {"cut_out_24v > 17V", [](ProgramSettings& p) { p.cut_out_24v = 17.0; },
       "cut_out_24v 17.00 V must be above 17 V"},
      {"cut_in_24v < 33V", [](ProgramSettings& p) { p.cut_in_24v = 33.0; },
       "cut_in_24v 33.00 V must be below 33 V"},
      {"cut_out_42v > 33V", [](ProgramSettings& p) { p.cut_out_42v = 33.0; },
       "cut_out_42v 33.00 V must be above 33 V"},
      {"cut_in_42v < 46V", [](ProgramSettings& p) { p.cut_in_42v = 46.0; },
       "cut_in_42v 46.00 V must be below 46 V"},
  };
  for (const auto& rule : rules) {
    SCOPED_TRACE(rule.name);
    auto p = standard();
    rule.breaks(p);
    EXPECT_EQ(why(p), rule.says);
  }
}

TEST(Fdc1Program, StandardIgnoresTheSpecialFields) {
  auto p = standard();
  p.nominal_voltage = 99;
  EXPECT_EQ(why(p), "valid");
}

TEST(Fdc1Program, SpecialRules) {
  const Rule rules[] = {
      {"cut_out < cut_in", [](ProgramSettings& p) { p.cut_in_special = 10.0; },
       "cut_out_special 10.00 V must be below cut_in_special 10.00 V"},
      {"cut_in < nominal", [](ProgramSettings& p) { p.nominal_voltage = 11.6; },
       "cut_in_special 11.60 V must be below nominal_voltage 11.60 V"},
      {"cut_out > 9V", [](ProgramSettings& p) { p.cut_out_special = 8.5; },
       "cut_out_special 8.50 V must be above 9 V"},
      {"nominal < 46V",
       [](ProgramSettings& p) {
         p.cut_in_special = 40.0;
         p.nominal_voltage = 46.0;
       },
       "nominal_voltage 46.00 V must be below 46 V"},
  };
  for (const auto& rule : rules) {
    SCOPED_TRACE(rule.name);
    auto p = special();
    rule.breaks(p);
    EXPECT_EQ(why(p), rule.says);
  }
  auto p = special();
  p.cut_out_12v = 0;  // the standard fields do not matter
  EXPECT_EQ(why(p), "valid");
}

TEST(Fdc1Program, ToProgramScalesVoltsBy1187) {
  // INPUT programming: bytes 9..20 are 1187 x volts.
  EXPECT_EQ(volts_to_raw(10.5), 12464);
  EXPECT_EQ(volts_to_raw(0.0), 0);
  EXPECT_EQ(volts_to_raw(11.5), 13651);  // 13650.5: half rounds away from zero
  EXPECT_EQ(volts_to_raw(11.6), 13769);  // 13769.2
  const Program s = to_program(standard());
  EXPECT_EQ(s.levels, (std::array<std::uint16_t, 6>{12464, 14838, 24927, 29675, 42732, 52228}));
  EXPECT_EQ(s.mode, 2);
  EXPECT_EQ(s.reserved, 0);
  const Program sp = to_program(special());
  // Special form: bytes 13..18 are 255, bytes 19..20 the nominal voltage.
  EXPECT_EQ(sp.levels, (std::array<std::uint16_t, 6>{11870, 13769, 0xFFFF, 0xFFFF, 0xFFFF, 16618}));
}

TEST(Fdc1Program, SlaveModeIsControlMemberTwo) {
  EXPECT_TRUE(is_slave(2));
  EXPECT_TRUE(is_slave(2 + 32 + 128));
  EXPECT_FALSE(is_slave(3));
  EXPECT_FALSE(is_slave(0));
}

}  // namespace
}  // namespace drivegate::fdc1
