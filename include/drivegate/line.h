// A serial line's settings and the one formula for how long a character takes on it: the bus
// engine's timeouts, the simulator host's wire pacing and the adapters' timing choices all read it.
#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string_view>

namespace drivegate {

enum class Parity : std::uint8_t { none, even, odd };
// Their names in drivegate.toml, on the command line and in the log, in enum order.
inline constexpr std::array<std::string_view, 3> kParityNames = {"none", "even", "odd"};
constexpr std::string_view to_string(Parity p) {
  return kParityNames.at(static_cast<std::size_t>(p));
}
constexpr std::optional<Parity> parse_parity(std::string_view name) {
  for (std::size_t i = 0; i < kParityNames.size(); ++i) {
    if (kParityNames[i] == name) return static_cast<Parity>(i);
  }
  return std::nullopt;
}

// The device's native line settings, used for a [[bus]] that does not set its own.
struct LineDefaults {
  std::uint32_t baud;
  Parity parity;
  std::uint8_t data_bits;
  std::uint8_t stop_bits;
  bool echo;  // one-wire line: the master hears its own bytes
};

// One character on an asynchronous serial line: a start bit, the data bits, the parity bit if
// any, and the stop bits.
constexpr unsigned bits_per_character(Parity parity, unsigned data_bits, unsigned stop_bits) {
  return 1u + data_bits + (parity == Parity::none ? 0u : 1u) + stop_bits;
}
constexpr std::chrono::nanoseconds character_time(std::uint32_t baud, Parity parity,
                                                  unsigned data_bits, unsigned stop_bits) {
  return std::chrono::nanoseconds(bits_per_character(parity, data_bits, stop_bits) *
                                  1'000'000'000ull / std::max<std::uint32_t>(baud, 1));
}
constexpr std::chrono::nanoseconds character_time(const LineDefaults& line) {
  return character_time(line.baud, line.parity, line.data_bits, line.stop_bits);
}

}  // namespace drivegate
