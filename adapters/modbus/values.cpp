#include "values.h"

#include <bit>
#include <cmath>
#include <limits>

namespace drivegate::modbus_device {
namespace {

// The 32 bits of a two-register value, by the point's word order.
std::uint32_t u32_of(const ProfilePoint& p, std::span<const std::uint16_t> w) {
  const std::uint16_t high = p.word_order == WordOrder::big ? w[0] : w[1];
  const std::uint16_t low = p.word_order == WordOrder::big ? w[1] : w[0];
  return (std::uint32_t{high} << 16) | low;
}

std::vector<std::uint16_t> words_of_u32(const ProfilePoint& p, std::uint32_t v) {
  const auto high = static_cast<std::uint16_t>(v >> 16);
  const auto low = static_cast<std::uint16_t>(v & 0xFFFF);
  if (p.word_order == WordOrder::big) return {high, low};
  return {low, high};
}

bool integral_scale_one(const ProfilePoint& p) {
  return p.type != ValueType::f32 && p.scale == 1.0;
}

}  // namespace

std::uint16_t masked(const ProfilePoint& p, std::uint16_t word) {
  if (!p.mask) return word;
  return static_cast<std::uint16_t>((word & *p.mask) >> std::countr_zero(*p.mask));
}

double raw_of(const ProfilePoint& p, std::span<const std::uint16_t> words) {
  switch (p.type) {
    case ValueType::bit:
      return words[0] != 0 ? 1.0 : 0.0;
    case ValueType::u16:
      return masked(p, words[0]);
    case ValueType::s16:
      return static_cast<std::int16_t>(words[0]);
    case ValueType::u32:
      return u32_of(p, words);
    case ValueType::s32:
      return static_cast<std::int32_t>(u32_of(p, words));
    case ValueType::f32:
      return std::bit_cast<float>(u32_of(p, words));
  }
  return 0.0;
}

Value value_of(const ProfilePoint& p, std::span<const std::uint16_t> words) {
  const double raw = raw_of(p, words);
  if (integral_scale_one(p)) return static_cast<std::int64_t>(raw);
  return raw * p.scale;
}

std::optional<std::vector<std::uint16_t>> words_for(const ProfilePoint& p, double v) {
  if (!std::isfinite(v)) return std::nullopt;
  if (p.type == ValueType::f32) {
    const double raw = v / p.scale;
    if (std::fabs(raw) > std::numeric_limits<float>::max()) return std::nullopt;
    return words_of_u32(p, std::bit_cast<std::uint32_t>(static_cast<float>(raw)));
  }
  // Integer types: the raw value the engineering value stands for, which must be whole (a
  // scale of 0.1 takes 12.3, not 12.34).
  const double exact = v / p.scale;
  const double raw = std::round(exact);
  if (std::fabs(raw - exact) > 1e-6 * std::max(1.0, std::fabs(exact))) return std::nullopt;
  double lo = 0;
  double hi = 0;
  switch (p.type) {
    case ValueType::bit:
      hi = 1;
      break;
    case ValueType::u16:
      hi = masked(p, 0xFFFF);
      break;
    case ValueType::s16:
      lo = -32768;
      hi = 32767;
      break;
    case ValueType::u32:
      hi = 4294967295.0;
      break;
    case ValueType::s32:
      lo = -2147483648.0;
      hi = 2147483647.0;
      break;
    case ValueType::f32:
      break;
  }
  if (raw < lo || raw > hi) return std::nullopt;
  if (p.mask) {
    const auto word = static_cast<std::uint32_t>(raw) << std::countr_zero(*p.mask);
    if ((word & ~std::uint32_t{*p.mask}) != 0) return std::nullopt;  // a bit outside the mask
    return std::vector<std::uint16_t>{static_cast<std::uint16_t>(word)};
  }
  if (p.width() == 1) {
    return std::vector<std::uint16_t>{
        static_cast<std::uint16_t>(static_cast<std::int64_t>(raw) & 0xFFFF)};
  }
  return words_of_u32(p, static_cast<std::uint32_t>(static_cast<std::int64_t>(raw) & 0xFFFFFFFF));
}

PointType served_type(const ProfilePoint& p) {
  switch (p.type) {
    case ValueType::s16:
      return PointType::i16;
    case ValueType::u32:
      return PointType::u32;
    case ValueType::s32:
      return PointType::i32;
    case ValueType::f32:
      return PointType::f32;
    default:
      return PointType::u16;
  }
}

}  // namespace drivegate::modbus_device
