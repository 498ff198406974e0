// A profile point's registers <-> its engineering value.
#include "values.h"

#include <gtest/gtest.h>

#include <cmath>

namespace drivegate::modbus_device {
namespace {

ProfilePoint of(ValueType type, double scale = 1.0, WordOrder order = WordOrder::big) {
  ProfilePoint p;
  p.type = type;
  p.scale = scale;
  p.word_order = order;
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
  EXPECT_EQ(value_of(of(ValueType::u32, 1, WordOrder::little), W{0xE240, 0x0001}),
            Value(std::int64_t{123456}));
  EXPECT_EQ(words_for(of(ValueType::s32, 1, WordOrder::little), -1), (W{0xFFFF, 0xFFFF}));
  // 12.5f = 0x41480000; little: low word first.
  EXPECT_DOUBLE_EQ(as_double(value_of(of(ValueType::f32, 1, WordOrder::little), W{0x0000, 0x4148})),
                   12.5);
  EXPECT_EQ(words_for(of(ValueType::f32), 12.5), (W{0x4148, 0x0000}));
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
}

TEST(ProfileValues, ServedTypes) {
  EXPECT_EQ(served_type(of(ValueType::s16, 0.1)), PointType::i16);
  EXPECT_EQ(served_type(of(ValueType::u32)), PointType::u32);
  EXPECT_EQ(served_type(of(ValueType::s32)), PointType::i32);
  EXPECT_EQ(served_type(of(ValueType::f32)), PointType::f32);
  EXPECT_EQ(served_type(of(ValueType::bit)), PointType::u16);
}

}  // namespace
}  // namespace drivegate::modbus_device
