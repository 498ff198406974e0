#include "program.h"

#include <cmath>
#include <cstdio>

namespace drivegate::fdc1 {
namespace {

std::string volts(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f V", v);
  return buf;
}

std::string rpm(std::uint16_t v) {
  return std::to_string(v) + " rpm";
}
std::string mode(std::uint8_t m) {
  return "mode " + std::to_string(m) + ": ";
}

}  // namespace

std::optional<std::string> validate_program(const ProgramSettings& p) {
  if (p.min_rpm < kMinRpm || p.min_rpm > kMaxRpm) {
    return "min_rpm " + rpm(p.min_rpm) + " is outside 1500..3500 rpm";
  }
  if (p.max_rpm < kMinRpm || p.max_rpm > kMaxRpm) {
    return "max_rpm " + rpm(p.max_rpm) + " is outside 1500..3500 rpm";
  }
  if (p.min_rpm > p.max_rpm) {  // drivegate's rule: a speed range must not be empty
    return "min_rpm " + rpm(p.min_rpm) + " is above max_rpm " + rpm(p.max_rpm);
  }
  if ((p.mode & kModeControlMask) == 1) {
    return mode(p.mode) + "control member 1 does not exist (0 normal, 2 slave, 3 proportional)";
  }
  if ((p.mode & kModeUnused) != 0) {
    return mode(p.mode) + "no member has the value 64";
  }
  if ((p.mode & kModeExternalLimits) != 0 && (p.mode & kModeSpecial) != 0) {
    // drivegate's reading: 0 / 16 / 32 are alternatives of one column of the mode table.
    return mode(p.mode) +
           "external battery limits (16) and special battery system (32) exclude each other";
  }
  if (p.special()) {
    if (!(p.cut_out_special < p.cut_in_special)) {
      return "cut_out_special " + volts(p.cut_out_special) + " must be below cut_in_special " +
             volts(p.cut_in_special);
    }
    if (!(p.cut_in_special < p.nominal_voltage)) {
      return "cut_in_special " + volts(p.cut_in_special) + " must be below nominal_voltage " +
             volts(p.nominal_voltage);
    }
    if (!(p.cut_out_special > kSpecialCutOutAbove)) {
      return "cut_out_special " + volts(p.cut_out_special) + " must be above 9 V";
    }
    if (!(p.nominal_voltage < kNominalBelow)) {
      return "nominal_voltage " + volts(p.nominal_voltage) + " must be below 46 V";
    }
    return std::nullopt;
  }
  struct Pair {
    const char* name;
    double cut_out, cut_in, out_above, in_below;
    const char* out_limit;
    const char* in_limit;
  };
  const Pair pairs[] = {
      {"12v", p.cut_out_12v, p.cut_in_12v, kCutOut12Above, kCutIn12Below, "9 V", "17 V"},
      {"24v", p.cut_out_24v, p.cut_in_24v, kCutOut24Above, kCutIn24Below, "17 V", "33 V"},
      {"42v", p.cut_out_42v, p.cut_in_42v, kCutOut42Above, kCutIn42Below, "33 V", "46 V"},
  };
  for (const auto& pair : pairs) {
    if (!(pair.cut_out < pair.cut_in)) {
      return std::string("cut_out_") + pair.name + " " + volts(pair.cut_out) +
             " must be below cut_in_" + pair.name + " " + volts(pair.cut_in);
    }
  }
  for (const auto& pair : pairs) {
    if (!(pair.cut_out > pair.out_above)) {
      return std::string("cut_out_") + pair.name + " " + volts(pair.cut_out) + " must be above " +
             pair.out_limit;
    }
    if (!(pair.cut_in < pair.in_below)) {
      return std::string("cut_in_") + pair.name + " " + volts(pair.cut_in) + " must be below " +
             pair.in_limit;
    }
  }
  return std::nullopt;
}

std::uint16_t volts_to_raw(double v) {
  const double raw = std::round(v * kVoltScale);
  if (!(raw >= 0)) return 0;
  if (raw > 0xFFFF) return 0xFFFF;
  return static_cast<std::uint16_t>(raw);
}

Program to_program(const ProgramSettings& p) {
  Program out;
  out.min_rpm = p.min_rpm;
  out.max_rpm = p.max_rpm;
  out.reserved = 0;  // INPUT programming, byte 7
  out.mode = p.mode;
  if (p.special()) {
    out.levels = {volts_to_raw(p.cut_out_special),
                  volts_to_raw(p.cut_in_special),
                  kUnusedLevel,
                  kUnusedLevel,
                  kUnusedLevel,
                  volts_to_raw(p.nominal_voltage)};
  } else {
    out.levels = {volts_to_raw(p.cut_out_12v), volts_to_raw(p.cut_in_12v),
                  volts_to_raw(p.cut_out_24v), volts_to_raw(p.cut_in_24v),
                  volts_to_raw(p.cut_out_42v), volts_to_raw(p.cut_in_42v)};
  }
  return out;
}

}  // namespace drivegate::fdc1
