// Reads a fuzz input as a script: small integers that choose the next step, and byte runs that
// are fed to the code under test. Reading past the end yields zeros and empty runs, so every
// harness terminates and every input is valid.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>

namespace drivegate::fuzz {

class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data, size) {}

  [[nodiscard]] bool empty() const { return at_ >= data_.size(); }
  [[nodiscard]] std::size_t remaining() const { return data_.size() - at_; }

  std::uint8_t u8() { return empty() ? 0 : data_[at_++]; }
  std::uint16_t u16() { return static_cast<std::uint16_t>((u8() << 8) | u8()); }
  std::uint32_t u32() { return (std::uint32_t{u16()} << 16) | u16(); }

  // Up to `n` bytes (fewer at the end of the input).
  std::span<const std::uint8_t> bytes(std::size_t n) {
    const std::size_t take = std::min(n, remaining());
    const auto out = data_.subspan(at_, take);
    at_ += take;
    return out;
  }
  std::span<const std::uint8_t> rest() { return bytes(remaining()); }

 private:
  std::span<const std::uint8_t> data_;
  std::size_t at_ = 0;
};

}  // namespace drivegate::fuzz
