#include "faults.h"

namespace drivegate::ed3100 {

FaultSet faults_of(std::uint16_t fault_word) {
  FaultSet s;
  if (tripped(fault_word)) s.set(Fault::other);
  return s;
}

std::uint32_t native_fault_of(std::uint16_t fault_word) {
  return tripped(fault_word) ? fault_word : 0u;
}

std::vector<Label> fault_code_labels() {
  return {{"no_fault", kNoFault}};
}

}  // namespace drivegate::ed3100
