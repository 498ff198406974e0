// Mapping of the eDrive's operating state and safety flags onto drivegate's unified faults.
// The table is in README.md ("Fault mapping"); the choices there are drivegate's.
#pragma once

#include <cstdint>

#include "drivegate/common.h"
#include "payloads.h"

namespace drivegate::unicla {

struct FaultView {
  FaultSet faults;
  bool warning = false;
  std::uint32_t native = 0;  // the op state when it is a Fault-* state, else 0
};

bool is_fault_state(std::uint8_t op_state);
// Starting, Running, Oil Balance Running: the motor turns or is about to.
bool is_running_state(std::uint8_t op_state);
// States in which the drive will not take a run command: Fault-*, Not Ready, Locked, Motor
// Thermal Inhibit.
bool refuses_run(std::uint8_t op_state);

FaultSet map_compressor_flags(std::uint16_t flags);
FaultSet map_motor_flags(std::uint16_t flags);
FaultSet map_electrical_flags(std::uint32_t flags);
FaultView map_faults(const Status& s);

}  // namespace drivegate::unicla
