// A profile's types, byte orders and labels (docs/profiles.md, "[[point]]"): what each reads as,
// and every way to get one wrong refused with the file and line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "profile.h"
#include "profile_support.h"

namespace drivegate::modbus_device::modbus_profile_types_test {
namespace {

using ::testing::ElementsAre;
using ::testing::FieldsAre;
using ::testing::HasSubstr;

const std::string kHead = "[profile]\nname = \"t\"\nsource = \"a manual\"\n";  // lines 1-3

// A profile of one point, whose [[point]] is line 4 and `body` starts on line 5.
std::variant<Profile, std::vector<std::string>> one(const std::string& body) {
  return parse_profile(kHead + "[[point]]\n" + body + "name = \"p\"\n", "p.toml");
}

ProfilePoint point(const std::string& body) {
  auto r = one(body);
  if (auto* errors = std::get_if<std::vector<std::string>>(&r)) {
    ADD_FAILURE() << ::testing::PrintToString(*errors);
    return {};
  }
  return std::get<Profile>(r).points.at(0);
}

std::vector<std::string> errors(const std::string& body) {
  auto r = one(body);
  if (auto* e = std::get_if<std::vector<std::string>>(&r)) return *e;
  ADD_FAILURE() << "accepted:\n" << body;
  return {};
}

TEST(ProfileTypes, SixtyFourBitTypesTakeFourRegisters) {
  for (const char* t : {"u64", "s64", "f64"}) {
    const ProfilePoint p =
        point(std::string("table = \"input\"\naddress = 10\ntype = \"") + t + "\"\n");
    EXPECT_EQ(p.width(), 4) << t;
    EXPECT_EQ(p.byte_order, ByteOrder::abcd);
  }
  // Four registers from 65532 end at 65535; from 65533 they run past it.
  EXPECT_EQ(point("table = \"input\"\naddress = 65532\ntype = \"u64\"\n").address, 65532);
  EXPECT_THAT(errors("table = \"input\"\naddress = 65533\ntype = \"u64\"\n"),
              ElementsAre(HasSubstr("p.toml:6: point.address: a point of 4 registers at 65533 "
                                    "runs past the last register, 65535")));
  // Wider than the device reads at once.
  EXPECT_THAT(parse_profile(kHead + "[modbus]\nmax_registers = 3\n[[point]]\nname = \"p\"\n"
                                    "table = \"input\"\naddress = 1\ntype = \"f64\"\n",
                            "p.toml"),
              testing::VariantWith<std::vector<std::string>>(ElementsAre(
                  HasSubstr("p.toml:10: point.type: takes 4 registers, more than the device"))));
}

TEST(ProfileTypes, ByteOrdersAndTheirShorthand) {
  const auto order = [](const std::string& type, const std::string& key) {
    return point("table = \"holding\"\naddress = 1\ntype = \"" + type + "\"\n" + key + "\n")
        .byte_order;
  };
  EXPECT_EQ(order("u32", "byte_order = \"abcd\""), ByteOrder::abcd);
  EXPECT_EQ(order("s32", "byte_order = \"badc\""), ByteOrder::badc);
  EXPECT_EQ(order("f32", "byte_order = \"cdab\""), ByteOrder::cdab);
  EXPECT_EQ(order("u64", "byte_order = \"dcba\""), ByteOrder::dcba);
  EXPECT_EQ(order("f64", "word_order = \"little\""), ByteOrder::cdab);
  EXPECT_EQ(order("s64", "word_order = \"big\""), ByteOrder::abcd);
  const std::string u32 = "table = \"holding\"\naddress = 1\ntype = \"u32\"\n";  // lines 5-7
  support::expect_refused(
      errors, {{u32 + "byte_order = \"abcd\"\nword_order = \"big\"\n",
                {"p.toml:9: point.word_order: is the shorthand of byte_order (big = abcd, "
                 "little = cdab): give one of them"}},
               {u32 + "byte_order = \"bacd\"\n", {"p.toml:8: point.byte_order: "}},
               {"table = \"holding\"\naddress = 1\ntype = \"s16\"\nbyte_order = \"badc\"\n",
                {"p.toml:8: point.byte_order: applies to the 32- and 64-bit types"}}});
}

TEST(ProfileTypes, StringsHaveRegistersAndAreReadOnly) {
  const ProfilePoint p =
      point("table = \"holding\"\naddress = 1\ntype = \"string\"\nregisters = 10\n");
  EXPECT_EQ(p.width(), 10);
  EXPECT_EQ(p.access, PointAccess::read);  // a holding string is served read-only
  EXPECT_EQ(point("table = \"input\"\naddress = 1\ntype = \"string\"\nregisters = 64\n"
                  "byte_order = \"badc\"\n")
                .byte_order,
            ByteOrder::badc);
  const std::string s = "table = \"holding\"\naddress = 1\ntype = \"string\"\n";  // lines 5-7
  support::expect_refused(
      errors,
      {{s, {"p.toml:4: point.registers: required key is missing"}},
       {s + "registers = 65\n", {"p.toml:8: point.registers: must be in 1..64 (got 65)"}},
       {s + "registers = 0\n", {"must be in 1..64 (got 0)"}},
       {s + "registers = 2\naccess = \"operate\"\n",
        {"p.toml:9: point.access: a string point is read-only"}},
       {s + "registers = 2\nmax = 3\n", {"p.toml:9: point.max: a string point is read-only"}},
       {s + "registers = 2\nbyte_order = \"cdab\"\n",
        {"p.toml:9: point.byte_order: a string takes byte_order \"abcd\""}},
       {s + "registers = 2\nword_order = \"big\"\n",
        {"p.toml:9: point.word_order: a string takes byte_order"}},
       {"table = \"holding\"\naddress = 1\ntype = \"u16\"\nregisters = 2\n",
        {"p.toml:8: point.registers: is a string point's length"}}});
  // 64 registers, more than a device that reads 60 at once.
  EXPECT_THAT(parse_profile(kHead + "[modbus]\nmax_registers = 60\n[[point]]\nname = \"p\"\n" + s +
                                "registers = 64\n",
                            "p.toml"),
              testing::VariantWith<std::vector<std::string>>(
                  ElementsAre(HasSubstr("takes 64 registers, more than the device reads"))));
}

TEST(ProfileTypes, AStringOrSixtyFourBitsCannotBeWhatTheCommonBlockWrites) {
  const std::string text = kHead +
                           "[[point]]\nname = \"serial\"\ntable = \"input\"\naddress = 1\n"
                           "type = \"string\"\nregisters = 4\n"  // lines 4-9
                           "[[point]]\nname = \"total\"\ntable = \"holding\"\naddress = 10\n"
                           "type = \"u64\"\n"  // lines 10-14
                           "[common]\nspeed_rpm = \"serial\"\nsetpoint_rpm = \"total\"\n"
                           "fault_code = { point = \"serial\" }\n";  // lines 15-18
  EXPECT_THAT(
      parse_profile(text, "p.toml"),
      testing::VariantWith<std::vector<std::string>>(ElementsAre(
          HasSubstr("p.toml:16: common.speed_rpm: must name a number, not a string"),
          HasSubstr("p.toml:17: common.setpoint_rpm: 'total' must be a holding point of type "
                    "u16, s16, u32, s32 or f32"),
          HasSubstr("p.toml:18: common.fault_code.point: must name a number, not a "
                    "string"))));
}

TEST(ProfileTypes, LabelsNameBitsAndValues) {
  const ProfilePoint bits = point(
      "table = \"holding\"\naddress = 1\ntype = \"u16\"\n"
      "bits = { 0 = \"ready\", 1 = \"running\", 3 = \"fault\", 15 = \"warning\" }\n");
  EXPECT_TRUE(bits.bit_labels);
  EXPECT_THAT(bits.labels, ElementsAre(FieldsAre("ready", 0u), FieldsAre("running", 1u),
                                       FieldsAre("fault", 3u), FieldsAre("warning", 15u)));
  // Keys decimal or "0x.." in any order; labels in value order.
  const ProfilePoint values = point(
      "table = \"input\"\naddress = 1\ntype = \"u32\"\n"
      "values = { \"0x11\" = \"undervoltage\", 0 = \"none\", 2 = \"overcurrent\" }\n");
  EXPECT_FALSE(values.bit_labels);
  EXPECT_THAT(values.labels, ElementsAre(FieldsAre("none", 0u), FieldsAre("overcurrent", 2u),
                                         FieldsAre("undervoltage", 0x11u)));
  // A bit field of 64 bits; "010" is ten, never octal.
  const ProfilePoint wide = point(
      "table = \"input\"\naddress = 1\ntype = \"u64\"\n"
      "bits = { 63 = \"top\", \"010\" = \"ten\" }\n");
  EXPECT_THAT(wide.labels, ElementsAre(FieldsAre("ten", 10u), FieldsAre("top", 63u)));
  // The values of a bit point.
  EXPECT_EQ(point("table = \"coil\"\naddress = 1\ntype = \"bit\"\n"
                  "values = { 0 = \"local\", 1 = \"remote\" }\n")
                .labels.size(),
            2u);
}

TEST(ProfileTypes, BadLabelsNameTheLine) {
  const std::string u16 = "table = \"input\"\naddress = 1\ntype = \"u16\"\n";  // lines 5-7
  support::expect_refused(
      errors,
      {{u16 + "bits = { 16 = \"beyond\" }\n",
        {"p.toml:8: point.bits: key '16' must be a bit number 0..15 of this u16"}},
       {"table = \"input\"\naddress = 1\ntype = \"u32\"\nbits = { 32 = \"x\" }\n",
        {"key '32' must be a bit number 0..31 of this u32"}},
       {u16 + "values = { 65536 = \"big\" }\n",
        {"p.toml:8: point.values: key '65536' must be a value 0..65535"}},
       {"table = \"input\"\naddress = 1\ntype = \"s16\"\n"
        "values = { 32768 = \"big\" }\n",
        {"must be a value 0..32767 of this s16"}},
       {u16 + "values = { \"0x11\" = \"a\", 17 = \"b\" }\n",
        {"p.toml:8: point.values: key '17' is 17, named already ('a')"}},
       {u16 + "values = { 1 = \"a\", 2 = \"a\" }\n",
        {"p.toml:8: point.values.2: 'a' names 1 already"}},
       {u16 + "values = { 1 = \"Fault\" }\n",
        {"p.toml:8: point.values.1: must be a name of 1..40 characters of a-z, 0-9 and '_' (got "
         "'Fault')"}},
       {u16 + "values = { 1 = \"" + std::string(41, 'a') + "\" }\n",
        {"must be a name of 1..40 characters"}},
       {u16 + "values = { 1 = \"\" }\n", {"must be a name of 1..40 characters"}},
       {u16 + "values = { 1 = 2 }\n", {"must be a name of 1..40 characters"}},
       {u16 + "values = { x1 = \"a\" }\n", {"key 'x1' must be a value"}},
       {u16 + "values = { \"-1\" = \"a\" }\n", {"key '-1' must be a value"}},
       {u16 + "values = {}\n", {"p.toml:8: point.values: must be a table such as"}},
       {u16 + "values = [\"a\"]\n", {"p.toml:8: point.values: must be a table such as"}},
       {u16 + "bits = { 0 = \"a\" }\nvalues = { 0 = \"b\" }\n",
        {"p.toml:9: point.values: a point has bits or values, not both"}},
       {u16 + "scale = 0.1\nvalues = { 0 = \"a\" }\n",
        {"p.toml:9: point.values: names raw values: a labelled point has scale 1"}},
       {"table = \"input\"\naddress = 1\ntype = \"f32\"\nvalues = { 0 = \"a\" }\n",
        {"p.toml:8: point.values: names the values or bits of an integer point, not of a f32"}},
       {"table = \"input\"\naddress = 1\ntype = \"f64\"\nbits = { 0 = \"a\" }\n", {"not of a f64"}},
       {"table = \"input\"\naddress = 1\ntype = \"string\"\nregisters = 2\n"
        "values = { 0 = \"a\" }\n",
        {"p.toml:9: point.values: names the values or bits of an integer point, not of a string"}},
       {"table = \"coil\"\naddress = 1\ntype = \"bit\"\nbits = { 0 = \"a\" }\n",
        {"a bit point has no bits but its own"}}});
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_profile_types_test
