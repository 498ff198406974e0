// Engineering values to registers and back: scale, sign, 32- and 64-bit values, floats, strings.
#include "gateway/value_codec.h"

#include <gtest/gtest.h>

namespace drivegate {
namespace {

std::vector<std::uint16_t> enc(const PointSpec& s, const Value& v) {
  std::vector<std::uint16_t> out(s.register_count());
  encode_value(s, v, out);
  return out;
}

TEST(ValueCodec, ScaleRoundsToTheNearestStep) {
  PointSpec s{.type = PointType::u16, .scale = 0.01};
  EXPECT_EQ(enc(s, 42.28), std::vector<std::uint16_t>{4228});
  EXPECT_EQ(enc(s, 0.005), std::vector<std::uint16_t>{1});  // half away from zero
  EXPECT_EQ(std::get<double>(*decode_value(s, std::vector<std::uint16_t>{5000})), 50.0);
}

TEST(ValueCodec, SignedAndSaturating) {
  PointSpec i16{.type = PointType::i16};
  EXPECT_EQ(enc(i16, std::int64_t{-1}), std::vector<std::uint16_t>{0xFFFF});
  EXPECT_EQ(enc(i16, std::int64_t{100000}), std::vector<std::uint16_t>{0x7FFF});
  EXPECT_EQ(std::get<std::int64_t>(*decode_value(i16, std::vector<std::uint16_t>{0xFFFE})), -2);
  PointSpec u16{.type = PointType::u16};
  EXPECT_EQ(enc(u16, std::int64_t{-5}), std::vector<std::uint16_t>{0});
  EXPECT_EQ(enc(u16, Value{}), std::vector<std::uint16_t>{0});
}

TEST(ValueCodec, ThirtyTwoBitsHighWordFirst) {
  PointSpec u32{.type = PointType::u32};
  EXPECT_EQ(enc(u32, std::int64_t{0x12345678}), (std::vector<std::uint16_t>{0x1234, 0x5678}));
  PointSpec i32{.type = PointType::i32};
  EXPECT_EQ(enc(i32, std::int64_t{-2}), (std::vector<std::uint16_t>{0xFFFF, 0xFFFE}));
  EXPECT_EQ(std::get<std::int64_t>(*decode_value(u32, std::vector<std::uint16_t>{1, 2})), 65538);
}

TEST(ValueCodec, FloatIsIeeeHighWordFirst) {
  PointSpec f{.type = PointType::f32};
  EXPECT_EQ(enc(f, 1.0), (std::vector<std::uint16_t>{0x3F80, 0x0000}));
  EXPECT_EQ(enc(f, -2.5), (std::vector<std::uint16_t>{0xC020, 0x0000}));
  EXPECT_EQ(std::get<double>(*decode_value(f, std::vector<std::uint16_t>{0x4049, 0x0FDB})),
            static_cast<double>(3.14159274f));
  // NaN and infinity are not values a client may write.
  EXPECT_FALSE(decode_value(f, std::vector<std::uint16_t>{0x7FC0, 0}));
}

TEST(ValueCodec, StringsTwoCharactersARegisterZeroPadded) {
  PointSpec s{.type = PointType::string, .string_registers = 3};
  EXPECT_EQ(enc(s, std::string("ABC")), (std::vector<std::uint16_t>{0x4142, 0x4300, 0x0000}));
  EXPECT_EQ(enc(s, std::string("ABCDEFGH")), (std::vector<std::uint16_t>{0x4142, 0x4344, 0x4546}));
  EXPECT_FALSE(decode_value(s, std::vector<std::uint16_t>{1, 2, 3}));
}

TEST(ValueCodec, SixtyFourBitsMostSignificantFirst) {
  using W = std::vector<std::uint16_t>;
  PointSpec u64{.type = PointType::u64};
  EXPECT_EQ(enc(u64, std::int64_t{0x1122334455667788}), (W{0x1122, 0x3344, 0x5566, 0x7788}));
  // A u64's int64_t is its 64 bits as they are (drivegate/point.h): 2^64 - 1 serves all ones,
  // and decodes as the nearest double (JSON, /metrics), the registers keeping the exact bits.
  EXPECT_EQ(enc(u64, std::int64_t{-1}), (W{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF}));
  EXPECT_EQ(std::get<double>(*decode_value(u64, W{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF})),
            18446744073709551615.0);
  EXPECT_EQ(std::get<std::int64_t>(*decode_value(u64, W{0x7FFF, 0xFFFF, 0xFFFF, 0xFFFF})),
            INT64_MAX);
  // A double saturates at the type's ends.
  EXPECT_EQ(enc(u64, -5.0), (W{0, 0, 0, 0}));
  EXPECT_EQ(enc(u64, 1e30), (W{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF}));
  PointSpec i64{.type = PointType::i64};
  EXPECT_EQ(enc(i64, std::int64_t{-2}), (W{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFE}));
  EXPECT_EQ(enc(i64, -1e30), (W{0x8000, 0, 0, 0}));
  EXPECT_EQ(std::get<std::int64_t>(*decode_value(i64, W{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFE})), -2);
  // Scaled: 1234.5 kWh at 0.1 is raw 12345.
  PointSpec scaled{.type = PointType::u64, .scale = 0.1};
  EXPECT_EQ(enc(scaled, 1234.5), (W{0, 0, 0, 12345}));
  EXPECT_DOUBLE_EQ(std::get<double>(*decode_value(scaled, W{0, 0, 0, 12345})), 1234.5);
  PointSpec f64{.type = PointType::f64};
  EXPECT_EQ(enc(f64, 1.5), (W{0x3FF8, 0, 0, 0}));
  EXPECT_EQ(enc(f64, Value{}), (W{0x7FF8, 0, 0, 0}));  // unknown: NaN
  EXPECT_EQ(std::get<double>(*decode_value(f64, W{0xC004, 0, 0, 0})), -2.5);
  EXPECT_FALSE(decode_value(f64, W{0x7FF0, 0, 0, 0}));  // infinity is not a value to write
  EXPECT_TRUE(has_word_order(u64) && has_word_order(i64) && has_word_order(f64));
  EXPECT_EQ(u64.register_count(), 4);
}

}  // namespace
}  // namespace drivegate
