// Sparkplug B payloads against bytes worked out by hand from the schema (spec Appendix A) and the
// protobuf encoding rules: field key = (number << 3) | wire type, varints 7 bits a byte, low
// first. Which value field each datatype uses is spec 6.4.16.
#include "mqtt/sparkplug_codec.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace drivegate::sparkplug {
namespace {

std::string bytes(std::initializer_list<unsigned> b) {
  std::string s;
  for (unsigned x : b) s.push_back(static_cast<char>(x));
  return s;
}

// An NDEATH: timestamp 1700000000000, metric bdSeq UInt64 3, no seq (spec 6.4.1).
TEST(SparkplugCodec, NodeDeathBytes) {
  Payload p;
  p.timestamp = 1700000000000;
  p.metrics.push_back({"bdSeq", DataType::uint64, MetricValue{std::uint64_t{3}}, {}});
  EXPECT_EQ(encode(p), bytes({
                           0x08, 0x80, 0xD0, 0x95, 0xFF, 0xBC, 0x31,  // 1 timestamp, varint
                           0x12, 0x0B,                                // 2 metrics, 11 bytes
                           0x0A, 0x05, 'b',  'd',  'S',  'e',  'q',   //   1 name
                           0x20, 0x08,                                //   4 datatype UInt64
                           0x58, 0x03,                                //   11 long_value
                       }));
}

// A DDATA: seq 7, speed_rpm Int16 -5 (int_value as 32-bit two's complement: 5-byte varint).
TEST(SparkplugCodec, NegativeInt16GoesInIntValueAsTwosComplement) {
  Payload p;
  p.timestamp = 1;
  p.seq = 7;
  p.metrics.push_back({"s", DataType::int16, MetricValue{std::int64_t{-5}}, {}});
  EXPECT_EQ(encode(p), bytes({
                           0x08, 0x01,                          // timestamp 1
                           0x12, 0x0B,                          // metric, 11 bytes
                           0x0A, 0x01, 's',                     //   name
                           0x20, 0x02,                          //   datatype Int16
                           0x50, 0xFB, 0xFF, 0xFF, 0xFF, 0x0F,  //   10 int_value 0xFFFFFFFB
                           0x18, 0x07,                          // 3 seq 7
                       }));
  std::string why;
  const auto back = decode(encode(p), why);
  ASSERT_TRUE(back) << why;
  EXPECT_EQ(back->metrics.at(0).value, MetricValue{std::int64_t{-5}});
  EXPECT_EQ(back->seq, 7u);
}

// Boolean in field 14, String in 15, Float in 12 (fixed32 little-endian), and a property set
// (field 9: keys 1, values 2 with type 1 and string_value 8).
TEST(SparkplugCodec, OtherTypesAndProperties) {
  Payload p;
  p.timestamp = 2;
  p.seq = 0;
  p.metrics.push_back({"b", DataType::boolean, MetricValue{true}, {}});
  p.metrics.push_back({"t", DataType::string, MetricValue{std::string("ok")}, {}});
  p.metrics.push_back({"f",
                       DataType::float32,
                       MetricValue{1.0},
                       {{"engUnit", DataType::string, MetricValue{std::string("s")}}}});
  EXPECT_EQ(encode(p),
            bytes({0x08, 0x02,                                                      // timestamp
                   0x12, 0x07, 0x0A, 0x01, 'b',  0x20, 0x0B, 0x70, 0x01,            // b: 14 boolean
                   0x12, 0x09, 0x0A, 0x01, 't',  0x20, 0x0C, 0x7A, 0x02, 'o', 'k',  // 15 string
                   0x12, 0x1C, 0x0A, 0x01, 'f',  0x20, 0x09,                        // f: Float
                   0x4A, 0x10,                                           //   9 properties
                   0x0A, 0x07, 'e',  'n',  'g',  'U',  'n',  'i',  't',  //     keys
                   0x12, 0x05, 0x08, 0x0C, 0x42, 0x01, 's',              //     values: String
                   0x65, 0x00, 0x00, 0x80, 0x3F,                         //   12 float 1.0f
                   0x18, 0x00}));                                        // seq 0
}

TEST(SparkplugCodec, NullIsFlaggedNotValued) {
  Payload p;
  p.metrics.push_back({"n", DataType::int32, MetricValue{}, {}});
  std::string why;
  const auto back = decode(encode(p), why);
  ASSERT_TRUE(back) << why;
  EXPECT_TRUE(std::holds_alternative<std::monostate>(back->metrics.at(0).value));
}

// A UInt32 arrives in int_value (the specification) or long_value (Eclipse Tahu): both read.
TEST(SparkplugCodec, UInt32FromEitherField) {
  std::string why;
  auto p = decode(bytes({0x12, 0x07, 0x0A, 0x01, 'u', 0x20, 0x07, 0x50, 0x2A}), why);
  ASSERT_TRUE(p) << why;
  EXPECT_EQ(p->metrics.at(0).value, MetricValue{std::uint64_t{42}});
  p = decode(bytes({0x12, 0x07, 0x0A, 0x01, 'u', 0x20, 0x07, 0x58, 0x2A}), why);
  ASSERT_TRUE(p) << why;
  EXPECT_EQ(p->metrics.at(0).value, MetricValue{std::uint64_t{42}});
}

TEST(SparkplugCodec, RefusesWhatIsNotAPayload) {
  std::string why;
  EXPECT_FALSE(decode(bytes({0xFF, 0xFF, 0xFF}), why));
  EXPECT_THAT(why, ::testing::HasSubstr("protobuf"));
  // Int16 declared, the value in string_value.
  EXPECT_FALSE(decode(bytes({0x12, 0x08, 0x0A, 0x01, 'x', 0x20, 0x02, 0x7A, 0x01, '1'}), why));
  EXPECT_THAT(why, ::testing::HasSubstr("'x'"));
}

TEST(SparkplugCodec, EmptyIsAPayloadWithNothingInIt) {
  std::string why;
  const auto p = decode("", why);
  ASSERT_TRUE(p);
  EXPECT_TRUE(p->metrics.empty());
  EXPECT_FALSE(p->seq);
}

}  // namespace
}  // namespace drivegate::sparkplug
