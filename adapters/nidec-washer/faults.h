// Section 8 fault table: the `Error` byte of every ACK is a bitmask; several bits may be set.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivegate/common.h"
#include "drivegate/point.h"

namespace drivegate::nidec {

// The unified faults the set bits of an `Error` byte stand for.
FaultSet map_faults(std::uint8_t error_bits);

// Bit labels of the section 8 bitmask (label value = bit number).
std::vector<Label> fault_bit_labels();

// The bit of a fault name of fault_bit_labels() ("stall" -> 0x08), for the simulator.
std::optional<std::uint8_t> fault_mask(std::string_view name);
std::string fault_names();  // "general|ipm_over_temperature|..."

}  // namespace drivegate::nidec
