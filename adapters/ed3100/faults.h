// The drive's fault word (0x0E01 word 1) as unified faults, and its labels. The document's fault
// code table is not legible (shared/specs/README.md, "ed3100": "expose it raw"), so every code is
// one unified fault and the raw code travels in native_fault and the drive_fault_code point.
#pragma once

#include <cstdint>
#include <vector>

#include "drivegate/common.h"
#include "drivegate/point.h"
#include "registers.h"

namespace drivegate::ed3100 {

[[nodiscard]] constexpr bool tripped(std::uint16_t fault_word) {
  return fault_word != kNoFault;
}
// Any code but FFFF: Fault::other (no legible table to map it further).
FaultSet faults_of(std::uint16_t fault_word);
// native_fault: the raw code, 0 when there is none.
std::uint32_t native_fault_of(std::uint16_t fault_word);
// Labels of the drive_fault_code point: only "no_fault" can be named.
std::vector<Label> fault_code_labels();

}  // namespace drivegate::ed3100
