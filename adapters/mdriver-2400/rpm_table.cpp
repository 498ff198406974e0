#include "rpm_table.h"

#include <cstdlib>

#include "codec.h"

namespace drivegate::mdriver {

std::int32_t rpm_of_code(std::uint8_t code) {
  if (code < kRpmTableSize) return kRpmTable[code];
  // Section 3 No.2: 0.3 rps (18 rpm) resolution; the table stops at 0x9F.
  return kRpmTable[kRpmTableSize - 1] + 18 * (code - static_cast<int>(kRpmTableSize - 1));
}

std::optional<std::uint8_t> code_for_rpm(std::int32_t rpm) {
  if (rpm < kRpmTable[kCodeLowestRun] || rpm > kRpmTable[kRpmTableSize - 1]) return std::nullopt;
  std::uint8_t best = kCodeLowestRun;
  for (std::size_t c = kCodeLowestRun; c < kRpmTableSize; ++c) {
    if (std::abs(kRpmTable[c] - rpm) < std::abs(kRpmTable[best] - rpm)) {
      best = static_cast<std::uint8_t>(c);
    }
  }
  return best;
}

}  // namespace drivegate::mdriver
