#include "gateway/value_codec.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

namespace drivegate {
namespace {

template <class T>
T saturate(double v) {
  if (std::isnan(v)) return 0;
  const auto lo = static_cast<double>(std::numeric_limits<T>::min());
  const auto hi = static_cast<double>(std::numeric_limits<T>::max());
  return static_cast<T>(std::llround(std::clamp(v, lo, hi)));
}

double scaled(const PointSpec& spec, const Value& value);

// The 64-bit integers: 2^63 and 2^64 are doubles exactly, and every double below them converts.
std::int64_t saturate_i64(double v) {
  constexpr double two63 = 9223372036854775808.0;
  if (std::isnan(v)) return 0;
  const double r = std::round(v);
  if (r >= two63) return std::numeric_limits<std::int64_t>::max();
  if (r < -two63) return std::numeric_limits<std::int64_t>::min();
  return static_cast<std::int64_t>(r);
}
std::uint64_t saturate_u64(double v) {
  constexpr double two64 = 18446744073709551616.0;
  if (std::isnan(v) || v <= 0) return 0;
  const double r = std::round(v);
  if (r >= two64) return std::numeric_limits<std::uint64_t>::max();
  return static_cast<std::uint64_t>(r);
}

// A 64-bit integer point's value: an integer at scale 1 goes as it is (a u64's bits, see
// drivegate/point.h), anything else through its engineering value.
std::uint64_t bits64(const PointSpec& spec, const Value& value) {
  const auto* i = std::get_if<std::int64_t>(&value);
  if (i != nullptr && (spec.scale == 1.0 || spec.scale == 0.0)) {
    return static_cast<std::uint64_t>(*i);
  }
  if (spec.type == PointType::u64) return saturate_u64(scaled(spec, value));
  return static_cast<std::uint64_t>(saturate_i64(scaled(spec, value)));
}

double scaled(const PointSpec& spec, const Value& value) {
  const double scale = spec.scale == 0.0 ? 1.0 : spec.scale;
  if (const auto* i = std::get_if<std::int64_t>(&value)) {
    if (scale == 1.0) return static_cast<double>(*i);
    return static_cast<double>(*i) / scale;
  }
  if (const auto* d = std::get_if<double>(&value)) return *d / scale;
  return 0.0;
}

void put32(std::uint32_t v, std::span<std::uint16_t> out) {
  out[0] = static_cast<std::uint16_t>(v >> 16);
  out[1] = static_cast<std::uint16_t>(v & 0xFFFF);
}

// Most significant register first, as put32.
void put64(std::uint64_t v, std::span<std::uint16_t> out) {
  for (std::size_t i = 0; i < 4; ++i) {
    out[i] = static_cast<std::uint16_t>(v >> (16 * (3 - i)));
  }
}

}  // namespace

void encode_value(const PointSpec& spec, const Value& value, std::span<std::uint16_t> out) {
  switch (spec.type) {
    case PointType::u16:
      out[0] = saturate<std::uint16_t>(scaled(spec, value));
      return;
    case PointType::i16:
      out[0] = static_cast<std::uint16_t>(saturate<std::int16_t>(scaled(spec, value)));
      return;
    case PointType::u32:
      put32(saturate<std::uint32_t>(scaled(spec, value)), out);
      return;
    case PointType::i32:
      put32(static_cast<std::uint32_t>(saturate<std::int32_t>(scaled(spec, value))), out);
      return;
    case PointType::f32:
      put32(std::bit_cast<std::uint32_t>(static_cast<float>(number_of(value))), out);
      return;
    case PointType::u64:
    case PointType::i64:
      put64(bits64(spec, value), out);
      return;
    case PointType::f64:
      put64(std::bit_cast<std::uint64_t>(number_of(value)), out);
      return;
    case PointType::string: {
      const auto* s = std::get_if<std::string>(&value);
      for (std::size_t r = 0; r < out.size(); ++r) {
        const auto ch = [&](std::size_t i) -> std::uint16_t {
          return s != nullptr && i < s->size() ? static_cast<unsigned char>((*s)[i]) : 0;
        };
        out[r] = static_cast<std::uint16_t>((ch(2 * r) << 8) | ch(2 * r + 1));
      }
      return;
    }
  }
}

double number_of(const Value& value) {
  if (std::holds_alternative<std::monostate>(value))
    return std::numeric_limits<double>::quiet_NaN();
  return as_double(value);
}

void encode_integer(PointType type, std::int64_t value, std::span<std::uint16_t> out) {
  const auto sat = [value](auto lo, auto hi) {
    return std::clamp<std::int64_t>(value, static_cast<std::int64_t>(lo),
                                    static_cast<std::int64_t>(hi));
  };
  switch (type) {
    case PointType::u16:
      out[0] = static_cast<std::uint16_t>(sat(0, 0xFFFF));
      return;
    case PointType::i16:
      out[0] = static_cast<std::uint16_t>(static_cast<std::int16_t>(sat(-32768, 32767)));
      return;
    case PointType::u32:
      put32(static_cast<std::uint32_t>(sat(0, 0xFFFFFFFFu)), out);
      return;
    case PointType::i32:
      put32(
          static_cast<std::uint32_t>(static_cast<std::int32_t>(sat(
              std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max()))),
          out);
      return;
    case PointType::f32:
      put32(std::bit_cast<std::uint32_t>(static_cast<float>(value)), out);
      return;
    case PointType::u64:
      put64(static_cast<std::uint64_t>(std::max<std::int64_t>(value, 0)), out);
      return;
    case PointType::i64:
      put64(static_cast<std::uint64_t>(value), out);
      return;
    case PointType::f64:
      put64(std::bit_cast<std::uint64_t>(static_cast<double>(value)), out);
      return;
    case PointType::string:
      return;
  }
}

std::optional<Value> decode_value(const PointSpec& spec, std::span<const std::uint16_t> in) {
  const double scale = spec.scale == 0.0 ? 1.0 : spec.scale;
  const auto engineering = [&](std::int64_t raw) -> Value {
    if (scale == 1.0) return raw;
    return static_cast<double>(raw) * scale;
  };
  const std::uint32_t u32 = in.size() >= 2 ? (std::uint32_t{in[0]} << 16) | in[1] : 0;
  std::uint64_t u64 = 0;
  if (in.size() >= 4) {
    for (std::size_t i = 0; i < 4; ++i) u64 = (u64 << 16) | in[i];
  }
  switch (spec.type) {
    case PointType::u16:
      return engineering(in[0]);
    case PointType::i16:
      return engineering(static_cast<std::int16_t>(in[0]));
    case PointType::u32:
      return engineering(u32);
    case PointType::i32:
      return engineering(static_cast<std::int32_t>(u32));
    case PointType::f32: {
      const auto f = std::bit_cast<float>(u32);
      if (!std::isfinite(f)) return std::nullopt;
      return static_cast<double>(f);
    }
    case PointType::u64:
      // Beyond an int64_t: the nearest double (the registers keep the exact bits).
      if (u64 > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
        return static_cast<double>(u64) * scale;
      }
      return engineering(static_cast<std::int64_t>(u64));
    case PointType::i64:
      return engineering(static_cast<std::int64_t>(u64));
    case PointType::f64: {
      const auto d = std::bit_cast<double>(u64);
      if (!std::isfinite(d)) return std::nullopt;
      return d;
    }
    case PointType::string:
      return std::nullopt;
  }
  return std::nullopt;
}

std::string decode_text(std::span<const std::uint16_t> in) {
  std::string s;
  s.reserve(2 * in.size());
  for (const std::uint16_t w : in) {
    s.push_back(static_cast<char>(w >> 8));
    s.push_back(static_cast<char>(w & 0xFF));
  }
  while (!s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

}  // namespace drivegate
