#include "faults.h"

#include <array>
#include <string_view>

#include "op_state.h"

namespace drivegate::unicla {

namespace {

// One bit of a flag word: its name in the document ("" where it says "X": unused) and the unified
// fault it stands for.
struct FlagBit {
  std::string_view name;
  Fault fault;
};

// "Compressor Safety Flags - Run, Start": refrigerant-side limits, every one a process limit.
constexpr std::array<FlagBit, 16> kCompressorFlags = {{
    {"", Fault::none},
    {"", Fault::none},
    {"", Fault::none},
    {"", Fault::none},
    {"Low Side Superheat High", Fault::process_limit},
    {"Low Side Superheat Low", Fault::process_limit},
    {"High Side Superheat High", Fault::process_limit},
    {"High Side Superheat Low", Fault::process_limit},
    {"Low Side Temperature High", Fault::process_limit},
    {"Low Side Temperature Low", Fault::process_limit},
    {"Low Side Pressure High", Fault::process_limit},
    {"Low Side Pressure Low", Fault::process_limit},
    {"High Side Temperature High", Fault::process_limit},
    {"High Side Temperature Low", Fault::process_limit},
    {"High Side Pressure High", Fault::process_limit},
    {"High Side Pressure Low", Fault::process_limit},
}};

// "Motor Safety Flags - Run, Start".
constexpr std::array<FlagBit, 16> kMotorFlags = {{
    {"", Fault::none},
    {"Switch Temperature Low", Fault::other},
    {"Switch Temperature High", Fault::drive_over_temperature},
    {"Motor Temperature Low", Fault::other},
    {"Motor Temperature High", Fault::motor_over_temperature},
    {"Motor Power Run Limit", Fault::overload},
    {"Motor Power Absolute Limit", Fault::overload},
    {"ST Motor Control Fault", Fault::hardware_fault},
    {"ST Motor Control - High FOC Rate", Fault::internal_error},
    {"ST Motor Control - Over voltage", Fault::over_voltage},
    {"ST Motor Control - Under Voltage", Fault::under_voltage},
    {"ST Motor Control - Over Temperature", Fault::drive_over_temperature},
    {"ST Motor Control - Startup Fail", Fault::stall},
    {"ST Motor Control - Speed Feedback Error", Fault::stall},
    {"ST Motor Control - Over Current", Fault::over_current},
    {"ST Motor Control - Software Error", Fault::internal_error},
}};

// "Electrical Safety Flags": supply rails of the FMC (bits 0..10) and CMC (16..23) boards.
constexpr std::array<FlagBit, 24> kElectricalFlags = {{
    {"FMC Data Invalid", Fault::hardware_fault},
    {"FMC 3.3V Fault", Fault::hardware_fault},
    {"FMC 5.0V Fault", Fault::hardware_fault},
    {"FMC VMON 24V Low", Fault::hardware_fault},
    {"FMC VMON 24V High", Fault::hardware_fault},
    {"FMC VMON UDXC 24V Low", Fault::hardware_fault},
    {"FMC VMON UDXC 24V High", Fault::hardware_fault},
    {"FMC VMON UDXC 5V Low", Fault::hardware_fault},
    {"FMC VMON UDXC 5V High", Fault::hardware_fault},
    {"FMC CT 5V Low", Fault::hardware_fault},
    {"FMC CT 5V High", Fault::hardware_fault},
    {"", Fault::none},
    {"", Fault::none},
    {"", Fault::none},
    {"", Fault::none},
    {"", Fault::none},
    {"CMC 3V3 Fault", Fault::hardware_fault},
    {"CMC 5V0 Fault", Fault::hardware_fault},
    {"CMC VMON 5V Low", Fault::hardware_fault},
    {"CMC VMON 5V High", Fault::hardware_fault},
    {"CMC AUX VMON VCC Low", Fault::hardware_fault},
    {"CMC AUX VMON VCC High", Fault::hardware_fault},
    {"CMC UDPC VCC Low", Fault::hardware_fault},
    {"CMC UDPC VCC High", Fault::hardware_fault},
}};

template <std::size_t N>
FaultSet map_flags(const std::array<FlagBit, N>& bits, std::uint32_t flags) {
  FaultSet f;
  for (std::size_t bit = 0; bit < N; ++bit) {
    if ((flags & (1u << bit)) != 0 && bits[bit].fault != Fault::none) f.set(bits[bit].fault);
  }
  return f;
}

template <std::size_t N>
std::vector<Label> labels_of(const std::array<FlagBit, N>& bits) {
  std::array<std::string_view, N> names{};
  for (std::size_t bit = 0; bit < N; ++bit) names[bit] = bits[bit].name;
  std::vector<Label> labels = labels_in_order(names);
  std::erase_if(labels, [](const Label& l) { return l.name.empty(); });  // "X"
  return labels;
}

}  // namespace

FaultSet map_compressor_flags(std::uint16_t flags) {
  return map_flags(kCompressorFlags, flags);
}

FaultSet map_motor_flags(std::uint16_t flags) {
  return map_flags(kMotorFlags, flags);
}

FaultSet map_electrical_flags(std::uint32_t flags) {
  return map_flags(kElectricalFlags, flags);
}

std::vector<Label> compressor_flag_labels() {
  return labels_of(kCompressorFlags);
}

std::vector<Label> motor_flag_labels() {
  return labels_of(kMotorFlags);
}

std::vector<Label> electrical_flag_labels() {
  return labels_of(kElectricalFlags);
}

FaultView map_faults(const Status& s) {
  // The run and start words of a kind say the same things at two moments: either counts.
  const FaultSet motor = map_motor_flags(s.motor_run_flags | s.motor_start_flags);
  FaultSet flagged = map_compressor_flags(s.compressor_run_flags | s.compressor_start_flags);
  flagged |= motor;
  flagged |= map_electrical_flags(s.electrical_flags);

  FaultView v;
  if (!is_fault_state(s.op_state)) {
    // A flag without a Fault-* state holds the drive back (or is about to): a warning.
    const auto st = static_cast<OpState>(s.op_state);
    v.warning = !flagged.empty() || st == OpState::wait_compressor_safety ||
                st == OpState::locked || st == OpState::motor_thermal_inhibit;
    return v;
  }
  v.native = s.op_state;
  v.faults = flagged;
  switch (static_cast<OpState>(s.op_state)) {
    case OpState::fault_compressor_safety:
      v.faults.set(Fault::process_limit);
      break;
    case OpState::fault_motor:
      if (motor.empty()) v.faults.set(Fault::other);  // no motor flag says more
      break;
    case OpState::fault_fmc:
    case OpState::fault_electrical:
      v.faults.set(Fault::hardware_fault);
      break;
    case OpState::fault_configuration:
      v.faults.set(Fault::config_error);
      break;
    case OpState::fault_xc_comms:
      v.faults.set(Fault::comm_lost);
      break;
    default:
      break;
  }
  return v;
}

}  // namespace drivegate::unicla
