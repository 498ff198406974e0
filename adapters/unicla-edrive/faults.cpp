#include "faults.h"

#include <array>

namespace drivegate::unicla {

namespace {

constexpr std::uint16_t kCompressorFlagsUsed = 0xFFF0;    // bits 0-3 are "X"
constexpr std::uint32_t kElectricalFlagsUsed = 0xFF07FF;  // bits 11-15 are "X"

// "Motor Safety Flags - Run, Start", bit n -> unified fault (none: bit 0 is "X").
constexpr std::array<Fault, 16> kMotorFlagFaults = {
    Fault::none,                    // 0  X
    Fault::other,                   // 1  Switch Temperature Low
    Fault::drive_over_temperature,  // 2  Switch Temperature High
    Fault::other,                   // 3  Motor Temperature Low
    Fault::motor_over_temperature,  // 4  Motor Temperature High
    Fault::overload,                // 5  Motor Power Run Limit
    Fault::overload,                // 6  Motor Power Absolute Limit
    Fault::hardware_fault,          // 7  ST Motor Control Fault
    Fault::internal_error,          // 8  ST Motor Control - High FOC Rate
    Fault::over_voltage,            // 9  ST Motor Control - Over voltage
    Fault::under_voltage,           // 10 ST Motor Control - Under Voltage
    Fault::drive_over_temperature,  // 11 ST Motor Control - Over Temperature
    Fault::stall,                   // 12 ST Motor Control - Startup Fail
    Fault::stall,                   // 13 ST Motor Control - Speed Feedback Error
    Fault::over_current,            // 14 ST Motor Control - Over Current
    Fault::internal_error,          // 15 ST Motor Control - Software Error
};

}  // namespace

bool is_fault_state(std::uint8_t s) {
  return s >= static_cast<std::uint8_t>(OpState::fault_compressor_safety) &&
         s <= static_cast<std::uint8_t>(OpState::fault_xc_comms);
}

bool is_running_state(std::uint8_t s) {
  const auto st = static_cast<OpState>(s);
  return st == OpState::starting || st == OpState::running || st == OpState::oil_balance_running;
}

bool refuses_run(std::uint8_t s) {
  const auto st = static_cast<OpState>(s);
  return is_fault_state(s) || st == OpState::not_ready || st == OpState::locked ||
         st == OpState::motor_thermal_inhibit || s >= kOpStateCount;
}

FaultSet map_compressor_flags(std::uint16_t flags) {
  FaultSet f;
  if ((flags & kCompressorFlagsUsed) != 0) f.set(Fault::process_limit);
  return f;
}

FaultSet map_motor_flags(std::uint16_t flags) {
  FaultSet f;
  for (std::size_t bit = 0; bit < kMotorFlagFaults.size(); ++bit) {
    if ((flags & (1u << bit)) != 0 && kMotorFlagFaults[bit] != Fault::none) {
      f.set(kMotorFlagFaults[bit]);
    }
  }
  return f;
}

FaultSet map_electrical_flags(std::uint32_t flags) {
  FaultSet f;
  if ((flags & kElectricalFlagsUsed) != 0) f.set(Fault::hardware_fault);  // FMC / CMC rails
  return f;
}

FaultView map_faults(const Status& s) {
  FaultSet flagged = map_compressor_flags(s.compressor_run_flags | s.compressor_start_flags);
  flagged |= map_motor_flags(s.motor_run_flags | s.motor_start_flags);
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
      if (map_motor_flags(s.motor_run_flags | s.motor_start_flags).empty()) {
        v.faults.set(Fault::other);
      }
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
