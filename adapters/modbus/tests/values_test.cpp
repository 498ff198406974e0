// A profile point's registers <-> its engineering value: every type and byte order, against
// register contents written out by hand from the definitions (docs/profiles.md, "Byte orders").
#include "values.h"

#include <gtest/gtest.h>

#include <cmath>
#include <initializer_list>
#include <optional>

namespace drivegate::modbus_device {
namespace {

ProfilePoint of(ValueType type, double scale = 1.0, ByteOrder order = ByteOrder::abcd,
                std::uint16_t registers = 0) {
  ProfilePoint p;
  p.type = type;
  p.scale = scale;
  p.byte_order = order;
  p.registers = registers;
  return p;
}

using W = std::vector<std::uint16_t>;

TEST(ProfileValues, SignedAndScaled) {
  EXPECT_EQ(value_of(of(ValueType::s16), W{0xFFFE}), Value(std::int64_t{-2}));
  EXPECT_EQ(value_of(of(ValueType::u16), W{0xFFFE}), Value(std::int64_t{65534}));
  EXPECT_DOUBLE_EQ(as_double(value_of(of(ValueType::s16, 0.1), W{15000})), 1500.0);
  EXPECT_EQ(words_for(of(ValueType::s16, 0.1), 1500.0), (W{15000}));
  EXPECT_EQ(words_for(of(ValueType::s16), -2), (W{0xFFFE}));
}

TEST(ProfileValues, TwoRegistersInEitherWordOrder) {
  // 0x0001E240 = 123456.
  EXPECT_EQ(value_of(of(ValueType::u32), W{0x0001, 0xE240}), Value(std::int64_t{123456}));
  EXPECT_EQ(value_of(of(ValueType::u32, 1, ByteOrder::cdab), W{0xE240, 0x0001}),
            Value(std::int64_t{123456}));
  EXPECT_EQ(words_for(of(ValueType::s32, 1, ByteOrder::cdab), -1), (W{0xFFFF, 0xFFFF}));
  // 12.5f = 0x41480000; cdab: low word first.
  EXPECT_DOUBLE_EQ(as_double(value_of(of(ValueType::f32, 1, ByteOrder::cdab), W{0x0000, 0x4148})),
                   12.5);
  EXPECT_EQ(words_for(of(ValueType::f32), 12.5), (W{0x4148, 0x0000}));
}

// The wire bytes of 0x11223344 (a = 0x11 the most significant) in each order, as the registers
// they make: abcd = 11 22 33 44, badc = 22 11 44 33, cdab = 33 44 11 22, dcba = 44 33 22 11.
struct Golden {
  ByteOrder order;
  W words;
};

// The registers of one value in each byte order (`golden`): each of `types` reads them as `read`
// and, given the value `written` (one a double holds exactly), writes it as them.
void expect_in_each_order(std::initializer_list<ValueType> types, const Golden (&golden)[4],
                          const Value& read, std::optional<double> written) {
  for (const auto& [order, words] : golden) {
    SCOPED_TRACE(kByteOrderNames[static_cast<std::size_t>(order)]);
    for (const ValueType type : types) {
      EXPECT_EQ(value_of(of(type, 1, order), words), read);
      if (written) {
        EXPECT_EQ(words_for(of(type, 1, order), *written), words);
      }
    }
  }
}

TEST(ProfileValues, ThirtyTwoBitsInEachByteOrder) {
  const Golden golden[] = {{ByteOrder::abcd, {0x1122, 0x3344}},
                           {ByteOrder::badc, {0x2211, 0x4433}},
                           {ByteOrder::cdab, {0x3344, 0x1122}},
                           {ByteOrder::dcba, {0x4433, 0x2211}}};
  expect_in_each_order({ValueType::u32, ValueType::s32}, golden, Value(std::int64_t{0x11223344}),
                       0x11223344);
  // -2 as s32 is FF FF FF FE: badc = FF FF FE FF, dcba = FE FF FF FF.
  EXPECT_EQ(words_for(of(ValueType::s32, 1, ByteOrder::badc), -2), (W{0xFFFF, 0xFEFF}));
  EXPECT_EQ(words_for(of(ValueType::s32, 1, ByteOrder::dcba), -2), (W{0xFEFF, 0xFFFF}));
  EXPECT_EQ(value_of(of(ValueType::s32, 1, ByteOrder::dcba), W{0xFEFF, 0xFFFF}),
            Value(std::int64_t{-2}));
  // 12.5f = 41 48 00 00: badc = 48 41 00 00, dcba = 00 00 48 41.
  const Golden f32[] = {{ByteOrder::abcd, {0x4148, 0x0000}},
                        {ByteOrder::badc, {0x4841, 0x0000}},
                        {ByteOrder::cdab, {0x0000, 0x4148}},
                        {ByteOrder::dcba, {0x0000, 0x4841}}};
  expect_in_each_order({ValueType::f32}, f32, Value(12.5), 12.5);
}

// 0x1122334455667788 (a = 0x11): abcd = 11 22 33 44 55 66 77 88, badc = 22 11 44 33 66 55 88
// 77, cdab = 77 88 55 66 33 44 11 22, dcba = 88 77 66 55 44 33 22 11.
TEST(ProfileValues, SixtyFourBitsInEachByteOrder) {
  const Golden golden[] = {{ByteOrder::abcd, {0x1122, 0x3344, 0x5566, 0x7788}},
                           {ByteOrder::badc, {0x2211, 0x4433, 0x6655, 0x8877}},
                           {ByteOrder::cdab, {0x7788, 0x5566, 0x3344, 0x1122}},
                           {ByteOrder::dcba, {0x8877, 0x6655, 0x4433, 0x2211}}};
  // Beyond 2^53: the value read keeps every bit (a double written would not).
  expect_in_each_order({ValueType::u64, ValueType::s64}, golden,
                       Value(std::int64_t{0x1122334455667788}), std::nullopt);
  // 2^53 - 1 = 00 1F FF FF FF FF FF FF, written in each order.
  const Golden max[] = {{ByteOrder::abcd, {0x001F, 0xFFFF, 0xFFFF, 0xFFFF}},
                        {ByteOrder::badc, {0x1F00, 0xFFFF, 0xFFFF, 0xFFFF}},
                        {ByteOrder::cdab, {0xFFFF, 0xFFFF, 0xFFFF, 0x001F}},
                        {ByteOrder::dcba, {0xFFFF, 0xFFFF, 0xFFFF, 0x1F00}}};
  expect_in_each_order({ValueType::u64}, max, Value(std::int64_t{9007199254740991}),
                       9007199254740991.0);
  // 1.5 = 3F F8 00 00 00 00 00 00.
  const Golden f64[] = {{ByteOrder::abcd, {0x3FF8, 0, 0, 0}},
                        {ByteOrder::badc, {0xF83F, 0, 0, 0}},
                        {ByteOrder::cdab, {0, 0, 0, 0x3FF8}},
                        {ByteOrder::dcba, {0, 0, 0, 0xF83F}}};
  expect_in_each_order({ValueType::f64}, f64, Value(1.5), 1.5);
  // -1 as s64 is all ones; as s64 -2 = FF..FE.
  EXPECT_EQ(words_for(of(ValueType::s64), -2), (W{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFE}));
  EXPECT_EQ(value_of(of(ValueType::s64), W{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFE}),
            Value(std::int64_t{-2}));
}

TEST(ProfileValues, AUnsignedSixtyFourBitValueKeepsItsTopBit) {
  // 0xFFFFFFFFFFFFFFFF, a drive's "not available": the value carries its 64 bits as they are
  // (drivegate/point.h), so that the register map serves them unchanged; its number is 2^64 - 1.
  const W ones{0xFFFF, 0xFFFF, 0xFFFF, 0xFFFF};
  EXPECT_EQ(value_of(of(ValueType::u64), ones), Value(std::int64_t{-1}));
  EXPECT_DOUBLE_EQ(raw_of(of(ValueType::u64), ones), 18446744073709551615.0);
  EXPECT_DOUBLE_EQ(raw_of(of(ValueType::s64), ones), -1.0);
  // With a scale, the engineering value is a double.
  EXPECT_DOUBLE_EQ(as_double(value_of(of(ValueType::u64, 0.001), W{0, 0, 0, 1500})), 1.5);
}

TEST(ProfileValues, SixtyFourBitWritesBeyondWhatADoubleSaysAreRefused) {
  EXPECT_EQ(words_for(of(ValueType::u64), 9007199254740992.0 * 2), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::s64), -9007199254740992.0 * 2), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::u64), -1), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::f64), std::nan("")), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::f64), INFINITY), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::f64, 1e-300), 1e300), std::nullopt);  // raw overflows
}

TEST(ProfileValues, WhatAPointCannotCarryIsRefused) {
  EXPECT_EQ(words_for(of(ValueType::u16), -1), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::u16), 65536), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::s16), 32768), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::s16, 0.1), 12.34), std::nullopt);  // not a whole 0.1
  EXPECT_EQ(words_for(of(ValueType::bit), 2), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::f32), std::nan("")), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::f32), INFINITY), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::f32), 1e300), std::nullopt);
  EXPECT_EQ(words_for(of(ValueType::string, 1, ByteOrder::abcd, 2), 1), std::nullopt);
}

TEST(ProfileValues, StringsFirstCharacterInTheHighByte) {
  const ProfilePoint s = of(ValueType::string, 1, ByteOrder::abcd, 4);
  // "ACS580" = 41 43 53 35 38 30, NUL-padded.
  EXPECT_EQ(value_of(s, W{0x4143, 0x5335, 0x3830, 0x0000}), Value(std::string("ACS580")));
  // Trailing spaces and NULs are dropped, inner ones kept (a space) or marked (a NUL).
  EXPECT_EQ(value_of(s, W{0x4120, 0x4200, 0x4320, 0x2000}), Value(std::string("A B?C")));
  EXPECT_EQ(words_for_text(s, "ACS580"), (W{0x4143, 0x5335, 0x3830, 0x0000}));
  // badc: the first character in the low byte.
  const ProfilePoint swapped = of(ValueType::string, 1, ByteOrder::badc, 4);
  EXPECT_EQ(value_of(swapped, W{0x4341, 0x3553, 0x3038, 0x0000}), Value(std::string("ACS580")));
  EXPECT_EQ(words_for_text(swapped, "ACS580"), (W{0x4341, 0x3553, 0x3038, 0x0000}));
  // Eight characters fit four registers, nine do not; only printable ASCII is written.
  EXPECT_TRUE(words_for_text(s, "12345678"));
  EXPECT_EQ(words_for_text(s, "123456789"), std::nullopt);
  EXPECT_EQ(words_for_text(s, "caf\xc3\xa9"), std::nullopt);
}

TEST(ProfileValues, AStringOfBytesThatAreNotTextShowsQuestionMarks) {
  // 64 registers of 0xFF: 128 characters, none printable.
  const ProfilePoint s = of(ValueType::string, 1, ByteOrder::abcd, 64);
  const W ff(64, 0xFFFF);
  EXPECT_EQ(value_of(s, ff), Value(std::string(128, '?')));
  EXPECT_TRUE(std::isnan(raw_of(s, ff)));
  // All NULs: the empty string.
  EXPECT_EQ(value_of(s, W(64, 0)), Value(std::string()));
}

TEST(ProfileValues, ServedTypes) {
  EXPECT_EQ(served_type(of(ValueType::s16, 0.1)), PointType::i16);
  EXPECT_EQ(served_type(of(ValueType::u32)), PointType::u32);
  EXPECT_EQ(served_type(of(ValueType::s32)), PointType::i32);
  EXPECT_EQ(served_type(of(ValueType::f32)), PointType::f32);
  EXPECT_EQ(served_type(of(ValueType::bit)), PointType::u16);
  EXPECT_EQ(served_type(of(ValueType::u64)), PointType::u64);
  EXPECT_EQ(served_type(of(ValueType::s64)), PointType::i64);
  EXPECT_EQ(served_type(of(ValueType::f64)), PointType::f64);
  EXPECT_EQ(served_type(of(ValueType::string, 1, ByteOrder::abcd, 3)), PointType::string);
}

}  // namespace
}  // namespace drivegate::modbus_device
