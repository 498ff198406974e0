// The unified vocabulary every adapter maps its native protocol onto: commands, fault codes and
// the status bits of the common register block. A PLC faceplate is written against these.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace drivegate {

// Values of the `command` holding register.
enum class Command : std::uint16_t {
  stop = 0,
  run_forward = 1,
  run_reverse = 2,
  quick_stop = 3,
  reset_fault = 4,
};

// Values of the `fault_code` input register. Ordered by value, not by severity (see severity()).
enum class Fault : std::uint16_t {
  none = 0,
  comm_lost = 1,
  over_voltage = 2,
  under_voltage = 3,
  over_current = 4,
  drive_over_temperature = 5,
  motor_over_temperature = 6,
  stall = 7,
  phase_loss = 8,
  overload = 9,
  supply_fault = 10,
  sensor_fault = 11,
  hardware_fault = 12,
  internal_error = 13,
  config_error = 14,
  process_limit = 15,
  fan_fault = 16,
  other = 17,
};
inline constexpr std::size_t kFaultCount = 18;

// Bits of the `status` input register (and of discrete inputs 0..7).
enum class StatusBit : std::uint8_t {
  online = 0,
  running = 1,
  fault = 2,
  warning = 3,
  comm_lost = 4,
  failsafe = 5,
  command_pending = 6,
};

// A set of unified faults: bit n is Fault(n). `fault_mask` holds it on the wire (u32).
class FaultSet {
 public:
  constexpr FaultSet() = default;
  constexpr explicit FaultSet(std::uint32_t bits) : bits_(bits) {}
  constexpr void set(Fault f) { bits_ |= bit(f); }
  constexpr void clear(Fault f) { bits_ &= ~bit(f); }
  [[nodiscard]] constexpr bool has(Fault f) const { return (bits_ & bit(f)) != 0; }
  [[nodiscard]] constexpr bool empty() const { return bits_ == 0; }
  [[nodiscard]] constexpr std::uint32_t bits() const { return bits_; }
  constexpr FaultSet& operator|=(FaultSet o) {
    bits_ |= o.bits_;
    return *this;
  }
  friend constexpr bool operator==(FaultSet, FaultSet) = default;

 private:
  static constexpr std::uint32_t bit(Fault f) { return 1u << static_cast<unsigned>(f); }
  std::uint32_t bits_ = 0;
};

// Names used in the register map, the config and the logs.
inline constexpr std::array<std::string_view, 5> kCommandNames = {
    "stop", "run_forward", "run_reverse", "quick_stop", "reset_fault"};
inline constexpr std::array<std::string_view, kFaultCount> kFaultNames = {"none",
                                                                          "comm_lost",
                                                                          "over_voltage",
                                                                          "under_voltage",
                                                                          "over_current",
                                                                          "drive_over_temperature",
                                                                          "motor_over_temperature",
                                                                          "stall",
                                                                          "phase_loss",
                                                                          "overload",
                                                                          "supply_fault",
                                                                          "sensor_fault",
                                                                          "hardware_fault",
                                                                          "internal_error",
                                                                          "config_error",
                                                                          "process_limit",
                                                                          "fan_fault",
                                                                          "other"};
inline constexpr std::array<std::string_view, 7> kStatusBitNames = {
    "online", "running", "fault", "warning", "comm_lost", "failsafe", "command_pending"};

constexpr std::string_view to_string(Command c) {
  return kCommandNames.at(static_cast<std::size_t>(c));
}
constexpr std::string_view to_string(Fault f) {
  return kFaultNames.at(static_cast<std::size_t>(f));
}
constexpr std::string_view to_string(StatusBit b) {
  return kStatusBitNames.at(static_cast<std::size_t>(b));
}
// Whether a command sets the motor turning.
constexpr bool is_run(Command c) {
  return c == Command::run_forward || c == Command::run_reverse;
}
constexpr std::optional<Command> command_from_value(std::uint16_t v) {
  if (v >= kCommandNames.size()) return std::nullopt;
  return static_cast<Command>(v);
}

// Severity rank of a fault (higher is more severe). `fault_code` shows the most severe member of
// the active set: faults that destroy hardware outrank lost communication, which outranks process
// limits. The order is drivegate's choice; no vendor document ranks its faults.
constexpr int severity(Fault f) {
  switch (f) {
    case Fault::none:
      return 0;
    case Fault::other:
      return 1;
    case Fault::process_limit:
      return 2;
    case Fault::config_error:
      return 3;
    case Fault::comm_lost:
      return 4;
    case Fault::sensor_fault:
      return 5;
    case Fault::fan_fault:
      return 6;
    case Fault::supply_fault:
      return 7;
    case Fault::under_voltage:
      return 8;
    case Fault::overload:
      return 9;
    case Fault::stall:
      return 10;
    case Fault::phase_loss:
      return 11;
    case Fault::motor_over_temperature:
      return 12;
    case Fault::drive_over_temperature:
      return 13;
    case Fault::over_voltage:
      return 14;
    case Fault::over_current:
      return 15;
    case Fault::internal_error:
      return 16;
    case Fault::hardware_fault:
      return 17;
  }
  return 0;
}
constexpr Fault most_severe(FaultSet s) {
  Fault best = Fault::none;
  for (std::size_t i = 1; i < kFaultCount; ++i) {
    const auto f = static_cast<Fault>(i);
    if (s.has(f) && severity(f) > severity(best)) best = f;
  }
  return best;
}

inline constexpr std::array<Command, 5> kAllCommands = {Command::stop, Command::run_forward,
                                                        Command::run_reverse, Command::quick_stop,
                                                        Command::reset_fault};

}  // namespace drivegate
