// The eDrive's faults onto drivegate's unified ones: the Fault-* operating states and the safety
// flags (eDrive RS485 Interface V16, "Interpreting Safety Flags"), and the flags' bit labels. The
// mapping is drivegate's choice; README.md, "Fault mapping", tables it.
#pragma once

#include <cstdint>
#include <vector>

#include "drivegate/common.h"
#include "drivegate/point.h"
#include "payloads.h"

namespace drivegate::unicla {

struct FaultView {
  FaultSet faults;
  bool warning = false;
  std::uint32_t native = 0;  // the op state when it is a Fault-* state, else 0
};

FaultSet map_compressor_flags(std::uint16_t flags);
FaultSet map_motor_flags(std::uint16_t flags);
FaultSet map_electrical_flags(std::uint32_t flags);
FaultView map_faults(const Status& s);

// Bit labels of the flag words, named as in the document; bits it marks "X" have none.
std::vector<Label> compressor_flag_labels();  // "Compressor Safety Flags - Run, Start"
std::vector<Label> motor_flag_labels();       // "Motor Safety Flags - Run, Start"
std::vector<Label> electrical_flag_labels();  // "Electrical Safety Flags", 24 bits

}  // namespace drivegate::unicla
