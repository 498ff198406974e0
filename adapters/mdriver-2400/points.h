// The adapter's own points: the fields of the run reply (section 3 No.2, R4..R11), the code the
// gateway last sent, and the state of the fixed-code check (section 3 No.1).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "drivegate/point.h"

namespace drivegate::mdriver {

// Index of each point in points() / values().
namespace pt {
enum : std::size_t {
  target_code,
  target_rpm,
  actual_code,
  error_code,
  ipm_temperature,
  info_1,
  info_2,
  info_3,
  sent_code,
  fixed_code_state,
  count,
};
}  // namespace pt

// Values of the fixed_code_state point.
enum class FixedCodeState : std::uint8_t { unchecked = 0, ok = 1, error = 2 };

std::vector<PointSpec> make_points();

}  // namespace drivegate::mdriver
