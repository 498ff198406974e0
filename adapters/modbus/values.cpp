#include "values.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace drivegate::modbus_device {
namespace {

std::uint16_t swap_bytes(std::uint16_t w) {
  return static_cast<std::uint16_t>((w << 8) | (w >> 8));
}

// The value's registers most significant first, high byte first in each: the point's byte
// order undone (profile.h, ByteOrder). Each order is its own inverse.
std::vector<std::uint16_t> in_abcd(ByteOrder order, std::span<const std::uint16_t> words) {
  std::vector<std::uint16_t> out(words.begin(), words.end());
  if (words_reversed(order)) std::reverse(out.begin(), out.end());
  if (bytes_swapped(order)) std::transform(out.begin(), out.end(), out.begin(), swap_bytes);
  return out;
}

// The 32 or 64 bits of a two- or four-register value.
std::uint64_t bits_of(const ProfilePoint& p, std::span<const std::uint16_t> words) {
  std::uint64_t v = 0;
  for (const std::uint16_t w : in_abcd(p.byte_order, words.first(p.width()))) v = (v << 16) | w;
  return v;
}

// The registers of the `width` low 16-bit words of `v`, in the point's byte order.
std::vector<std::uint16_t> words_of_bits(const ProfilePoint& p, std::uint64_t v) {
  std::vector<std::uint16_t> w(p.width());
  for (std::size_t i = 0; i < w.size(); ++i) {
    w[i] = static_cast<std::uint16_t>(v >> (16 * (w.size() - 1 - i)));
  }
  return in_abcd(p.byte_order, w);
}

bool integral_scale_one(const ProfilePoint& p) {
  return !is_float(p.type) && p.scale == 1.0;
}

// 2^53: every integer up to it is a double exactly; a 64-bit write beyond it is refused rather
// than rounded.
constexpr double kExactInDouble = 9007199254740992.0;

bool printable(unsigned char c) {
  return c >= 0x20 && c <= 0x7E;
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
    case ValueType::u64:
      return static_cast<double>(bits_of(p, words));
    case ValueType::s32:
      return static_cast<std::int32_t>(static_cast<std::uint32_t>(bits_of(p, words)));
    case ValueType::s64:
      return static_cast<double>(static_cast<std::int64_t>(bits_of(p, words)));
    case ValueType::f32:
      return std::bit_cast<float>(static_cast<std::uint32_t>(bits_of(p, words)));
    case ValueType::f64:
      return std::bit_cast<double>(bits_of(p, words));
    case ValueType::string:
      return std::numeric_limits<double>::quiet_NaN();
  }
  return 0.0;
}

std::string text_of(const ProfilePoint& p, std::span<const std::uint16_t> words) {
  std::string s;
  s.reserve(2 * words.size());
  for (const std::uint16_t w : in_abcd(p.byte_order, words.first(p.width()))) {
    s.push_back(static_cast<char>(w >> 8));
    s.push_back(static_cast<char>(w & 0xFF));
  }
  while (!s.empty() && (s.back() == '\0' || s.back() == ' ')) s.pop_back();
  for (char& c : s) {
    if (!printable(static_cast<unsigned char>(c))) c = '?';
  }
  return s;
}

Value value_of(const ProfilePoint& p, std::span<const std::uint16_t> words) {
  if (p.type == ValueType::string) return text_of(p, words);
  if (integral_scale_one(p) && p.width() == 4) {
    // All 64 bits, a u64's too (drivegate/point.h, Value).
    return static_cast<std::int64_t>(bits_of(p, words));
  }
  const double raw = raw_of(p, words);
  if (integral_scale_one(p)) return static_cast<std::int64_t>(raw);
  return raw * p.scale;
}

std::optional<std::vector<std::uint16_t>> words_for(const ProfilePoint& p, double v) {
  if (!std::isfinite(v) || p.type == ValueType::string) return std::nullopt;
  if (p.type == ValueType::f32) {
    const double raw = v / p.scale;
    if (std::fabs(raw) > std::numeric_limits<float>::max()) return std::nullopt;
    return words_of_bits(p, std::bit_cast<std::uint32_t>(static_cast<float>(raw)));
  }
  if (p.type == ValueType::f64) {
    const double raw = v / p.scale;
    if (!std::isfinite(raw)) return std::nullopt;
    return words_of_bits(p, std::bit_cast<std::uint64_t>(raw));
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
    case ValueType::u64:
      hi = kExactInDouble;
      break;
    case ValueType::s64:
      lo = -kExactInDouble;
      hi = kExactInDouble;
      break;
    case ValueType::f32:
    case ValueType::f64:
    case ValueType::string:
      break;
  }
  if (raw < lo || raw > hi) return std::nullopt;
  if (p.mask) {
    const auto word = static_cast<std::uint32_t>(raw) << std::countr_zero(*p.mask);
    if ((word & ~std::uint32_t{*p.mask}) != 0) return std::nullopt;  // a bit outside the mask
    return std::vector<std::uint16_t>{static_cast<std::uint16_t>(word)};
  }
  const auto whole = static_cast<std::int64_t>(raw);
  if (p.width() == 1) {
    return std::vector<std::uint16_t>{static_cast<std::uint16_t>(whole & 0xFFFF)};
  }
  return words_of_bits(p, static_cast<std::uint64_t>(whole));
}

std::optional<std::vector<std::uint16_t>> words_for_text(const ProfilePoint& p,
                                                         std::string_view text) {
  if (p.type != ValueType::string || text.size() > 2 * std::size_t{p.width()}) return std::nullopt;
  if (!std::all_of(text.begin(), text.end(),
                   [](char c) { return printable(static_cast<unsigned char>(c)); })) {
    return std::nullopt;
  }
  std::vector<std::uint16_t> w(p.width());
  const auto at = [&](std::size_t i) -> std::uint16_t {
    return i < text.size() ? static_cast<unsigned char>(text[i]) : 0;
  };
  for (std::size_t i = 0; i < w.size(); ++i) {
    w[i] = static_cast<std::uint16_t>((at(2 * i) << 8) | at(2 * i + 1));
  }
  return in_abcd(p.byte_order, w);
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
    case ValueType::u64:
      return PointType::u64;
    case ValueType::s64:
      return PointType::i64;
    case ValueType::f64:
      return PointType::f64;
    case ValueType::string:
      return PointType::string;
    default:
      return PointType::u16;
  }
}

}  // namespace drivegate::modbus_device
