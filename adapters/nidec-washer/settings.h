// The device's options: the schema the gateway validates them against, and the values the driver
// uses.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "drivegate/options.h"

namespace drivegate::nidec {

inline constexpr std::array<OptionSpec, 4> kOptionSchema = {{
    // 5.1: ping byte 3, the washer volume as a distinguishing number (0x07 = 7 kg).
    {"platform", OptionType::integer, "7",
     "washer platform sent in the ping (5.1), e.g. 7 for a 7 kg washer", 0, 255},
    // 5.1: ping bytes 4-5, 16 bits; 0 leaves the inverter's own table unadjusted.
    {"empty_raw_weight", OptionType::integer, "0",
     "empty-basket raw weight sent in the ping (5.1); 0 = no adjustment", 0, 65535},
    // 5.3 / 5.4 / 5.6 / 5.14: 16-bit accel time in 100 ms units, at most 6553.5 s.
    {"accel_time_ms", OptionType::integer, "3000",
     "initial accel time of CW/CCW/spin/free-shaft spin (sent in 100 ms units, 5.3)", 0, 6553500},
    // Section 6: the same frame is resent after 100 ms without a reply.
    {"attempts", OptionType::integer, "3",
     "identical sends per bus turn before giving the line to others (section 6: resend)", 1, 20},
}};

struct Settings {
  std::uint8_t platform = 7;           // 5.1 ping byte 3
  std::uint16_t empty_raw_weight = 0;  // 5.1 ping bytes 4-5
  std::uint16_t accel_100ms = 30;      // 5.3: accel time in 100 ms units
  std::uint8_t attempts = 3;           // identical sends per turn (section 6: resend)
};

// The options as the driver uses them, accel_time_ms rounded to the 100 ms the frame carries.
// Never nullopt: no two options can contradict each other, and the schema's ranges are the
// fields' own (settings.cpp has the compiler hold them to that), so every value fits its frame.
std::optional<Settings> parse_settings(const Options& options, std::string& error);

}  // namespace drivegate::nidec
