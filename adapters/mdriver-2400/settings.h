// The device's options: the schema the gateway validates them against, and the values the driver
// and the simulator use.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "drivegate/options.h"

namespace drivegate::mdriver {

inline constexpr std::array<OptionSpec, 3> kOptionSchema = {{
    // Section 3: master (PC) address [00].
    {"master_address", OptionType::integer, "0",
     "the gateway's own address (D0 of every frame it sends)", 0, 255},
    // Section 3 No.2 and 連続運転モード: D5 = 0x01 (normal, 360 rpm/s) or 0xFF (continuous).
    {"mode", OptionType::string, "normal",
     "frequency change time D5: normal (0x01, 360 rpm/s) or continuous (0xFF)", 0, 0,
     "normal|continuous"},
    // Error table, 0x0C: the driver stops after 6 s without a frame; 5 s leaves a margin.
    {"keepalive_ms", OptionType::integer, "1000",
     "longest gap between two run commands (the driver trips after 6 s)", 100, 5000},
}};

struct Settings {
  std::uint8_t master = 0x00;  // Section 3: マスター(PC)アドレス [00]
  std::uint8_t change = 0x01;  // D5: 0x01 normal, 0xFF continuous
  std::chrono::milliseconds keepalive{1000};
};

// The options as the driver and simulator use them. The schema has checked every value, and no
// two options contradict each other; nullopt with `error` naming the option is kept for a value
// the schema let through that the protocol cannot carry.
std::optional<Settings> parse_settings(const Options& options, std::string& error);

// The device's one-byte address (section 2), which must differ from master_address: nullopt with
// `error` otherwise.
std::optional<std::uint8_t> device_address(std::uint32_t address, const Settings& settings,
                                           std::string& error);

}  // namespace drivegate::mdriver
