// Bytes on a line, and big-endian field helpers for codecs. Every protocol drivegate speaks puts
// the high byte first unless its document says otherwise; codecs that differ say so where they
// differ.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace drivegate {

using Bytes = std::vector<std::uint8_t>;         // a frame, owned
using ByteView = std::span<const std::uint8_t>;  // bytes received or to decode, borrowed

constexpr std::uint16_t be16(std::uint8_t hi, std::uint8_t lo) {
  return static_cast<std::uint16_t>((hi << 8) | lo);
}
// The big-endian 16-bit field at byte `at` of `b` (the caller has checked the length).
constexpr std::uint16_t be16_at(ByteView b, std::size_t at) {
  return be16(b[at], b[at + 1]);
}
constexpr std::uint8_t hi8(std::uint16_t v) {
  return static_cast<std::uint8_t>(v >> 8);
}
constexpr std::uint8_t lo8(std::uint16_t v) {
  return static_cast<std::uint8_t>(v & 0xFF);
}

inline void put_be16(std::vector<std::uint8_t>& out, std::uint16_t v) {
  out.push_back(hi8(v));
  out.push_back(lo8(v));
}

}  // namespace drivegate
