// The device's options, checked and turned into the values the driver and simulator use.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "drivegate/driver.h"

namespace drivegate::mdriver {

inline constexpr const char* kOptMasterAddress = "master_address";
inline constexpr const char* kOptMode = "mode";
inline constexpr const char* kOptKeepalive = "keepalive_ms";

struct Config {
  std::uint8_t master = 0x00;  // Section 3: マスター(PC)アドレス [00]
  std::uint8_t device = 0x01;  // Section 3: スレーブ(ドライバ)アドレス [01]
  std::uint8_t change = 0x01;  // D5: 0x01 normal, 0xFF continuous
  Millis keepalive{1000};
};

// nullopt and a one-line `error` when the options do not make a device (e.g. master address equal
// to the device address, or an address over 0xFF).
std::optional<Config> make_config(std::uint32_t address, const Options& options,
                                  std::string& error);

}  // namespace drivegate::mdriver
