// Checking a description by hand (inspect.h): bytes decoded into named fields, a message encoded
// from field values with the rest as the description sends it.
#include "inspect.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "protocol_fixture.h"

namespace drivegate::framed {
namespace {

using test::hex;
using test::shipped;
using ::testing::HasSubstr;

TEST(Inspect, HexIsReadWithBlanksAndPrefixes) {
  EXPECT_EQ(parse_hex("A5 05 0x00 ff"), hex("A5 05 00 FF"));
  EXPECT_EQ(parse_hex("a505"), hex("A5 05"));
  EXPECT_FALSE(parse_hex("A5 0").has_value());
  EXPECT_FALSE(parse_hex("A5 zz").has_value());
  EXPECT_EQ(hex_text(hex("A5 05 00")), "A5 05 00");
}

TEST(Inspect, DecodesEveryFrameInTheBytesFieldByField) {
  const auto d = shipped("nidec-washer");
  const std::string text = decode_text(
      *d, hex("A5 05 00 03 20 23 A0 00 A5 09 03 20 00 1E 00 00 00 00 91"), std::nullopt);
  EXPECT_THAT(text, HasSubstr("request_ack (reply, 7 bytes): A5 05 00 03 20 23 A0\n"
                              "  error = 0\n  speed = 800\n  weight = 35\n"
                              "  checksum = 0xA0 (xor, good)\n"));
  EXPECT_THAT(text, HasSubstr("bad header: 1 byte dropped: 00\n"));
  EXPECT_THAT(text, HasSubstr("cw (request, 11 bytes): A5 09 03 20 00 1E 00 00 00 00 91\n"
                              "  speed = 800\n  accel_time = 30\n"));
  EXPECT_THAT(decode_text(*d, hex("A5 05 00 03 20 23 A1"), Direction::reply),
              HasSubstr("bad checksum: 7 bytes dropped"));
  EXPECT_THAT(decode_text(*d, hex("A5 05 00"), Direction::reply), HasSubstr("incomplete: 3 bytes"));
}

TEST(Inspect, EncodesAMessageTheRestAsTheDescriptionSendsIt) {
  const auto d = shipped("nidec-washer");
  Options options;
  options.set("platform", std::int64_t{8});
  options.set("empty_raw_weight", std::int64_t{300});
  options.set("accel_time_ms", std::int64_t{3000});
  options.set("attempts", std::int64_t{3});
  std::string error;
  EXPECT_EQ(encode_message(*d, "ping", {}, options, error), hex("A5 02 08 01 2C 00 00 00 00 00 82"))
      << error;
  // The accel time is the point's initial value (from accel_time_ms), in 100 ms units.
  EXPECT_EQ(encode_message(*d, "cw", {{"speed", 800}}, options, error),
            hex("A5 09 03 20 00 1E 00 00 00 00 91"));
  EXPECT_FALSE(encode_message(*d, "cww", {}, options, error).has_value());
  EXPECT_THAT(error, HasSubstr("no message 'cww' in nidec-washer (ping, request, cw"));
  EXPECT_FALSE(encode_message(*d, "cw", {{"sped", 1}}, options, error).has_value());
  EXPECT_THAT(error, HasSubstr("message 'cw' has no field 'sped' (speed, accel_time)"));
}

TEST(Inspect, TheDissectorsDataNamesEveryTokenAndCheck) {
  const std::string lua = lua_table(*shipped("fdc1"));
  EXPECT_THAT(lua, HasSubstr("name = \"fdc1\""));
  EXPECT_THAT(lua, HasSubstr("{ name = \"odd\", kind = \"xor\", width = 1"));
  EXPECT_THAT(lua,
              HasSubstr("{ offset = 3, width = 1, field = \"alarm_code\", encoding = \"uint\""));
  EXPECT_THAT(lua, HasSubstr("name = \"co\""));
}

}  // namespace
}  // namespace drivegate::framed
