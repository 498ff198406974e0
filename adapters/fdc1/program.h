// The 22-byte programming frame in engineering units, and the limits the document sets on it
// (INPUT, "Programming mode + parameters"; the speed range kMinRpm..kMaxRpm is in codec.h). Pure.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "codec.h"

namespace drivegate::fdc1 {

// Members of the mode byte (INPUT, "The mode byte is the sum of the next members").
inline constexpr std::uint8_t kModeControlMask = 0x03;   // 0 normal, 2 slave, 3 proportional
inline constexpr std::uint8_t kModeSlave = 2;            // "2: external thermostat = SLAVE MODE"
inline constexpr std::uint8_t kModeProportional = 3;     // "3: speed proportional to battery"
inline constexpr std::uint8_t kModeSpeedMask = 0x0C;     // 0 normal, 4 smart, 8 sleep, 12 eco
inline constexpr std::uint8_t kModeSmartSpeed = 4;       // "4: Smart Speed"
inline constexpr std::uint8_t kModeSleep = 8;            // "8: Sleep mode"
inline constexpr std::uint8_t kModeEnergySaving = 12;    // "12: Energy Saving Sleep mode"
inline constexpr std::uint8_t kModeExternalLimits = 16;  // "16: external battery limits"
inline constexpr std::uint8_t kModeSpecial = 32;         // "32: special battery system" (bit 5)
inline constexpr std::uint8_t kModeUnused = 64;          // no member has this value
inline constexpr std::uint8_t kModeDelay = 128;          // "128: 3 minutes delay"

// INPUT, "must fulfill the next requirements" (volts).
inline constexpr double kCutOut12Above = 9.0;       // cut_out_12V > 9V
inline constexpr double kCutIn12Below = 17.0;       // cut_in_12V < 17V
inline constexpr double kCutOut24Above = 17.0;      // cut_out_24V > 17V
inline constexpr double kCutIn24Below = 33.0;       // cut_in_24V < 33V
inline constexpr double kCutOut42Above = 33.0;      // cut_out_42V > 33V
inline constexpr double kCutIn42Below = 46.0;       // cut_in_42V < 46V
inline constexpr double kSpecialCutOutAbove = 9.0;  // cut_out_special > 9V
inline constexpr double kNominalBelow = 46.0;       // nominal_voltage < 46V

struct ProgramSettings {
  std::uint16_t min_rpm = 0;
  std::uint16_t max_rpm = 0;
  std::uint8_t mode = 0;  // bit 5 selects the special battery system form
  // Standard battery system (mode bit 5 = 0), volts.
  double cut_out_12v = 0, cut_in_12v = 0;
  double cut_out_24v = 0, cut_in_24v = 0;
  double cut_out_42v = 0, cut_in_42v = 0;
  // Special battery system (mode bit 5 = 1), volts.
  double cut_out_special = 0, cut_in_special = 0, nominal_voltage = 0;

  [[nodiscard]] bool special() const { return (mode & kModeSpecial) != 0; }
};

// The first rule `p` breaks, as one line of text naming the field, or nothing when every limit
// the document lists (and the two drivegate adds, see README) holds.
std::optional<std::string> validate_program(const ProgramSettings& p);

// Volts -> 1187 x volts rounded to the nearest count; the frame fields for `p`'s form.
std::uint16_t volts_to_raw(double volts);
Program to_program(const ProgramSettings& p);

// Whether `mode` is in slave mode (specs README: mode & 3 == 2).
constexpr bool is_slave(std::uint8_t mode) {
  return (mode & kModeControlMask) == kModeSlave;
}

}  // namespace drivegate::fdc1
