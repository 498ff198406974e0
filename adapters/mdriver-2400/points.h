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
inline constexpr std::size_t target_code = 0;
inline constexpr std::size_t target_rpm = 1;
inline constexpr std::size_t actual_code = 2;
inline constexpr std::size_t error_code = 3;
inline constexpr std::size_t ipm_temperature = 4;
inline constexpr std::size_t info_1 = 5;
inline constexpr std::size_t info_2 = 6;
inline constexpr std::size_t info_3 = 7;
inline constexpr std::size_t sent_code = 8;
inline constexpr std::size_t fixed_code_state = 9;
inline constexpr std::size_t count = 10;
}  // namespace pt

// Values of the fixed_code_state point.
enum class FixedCodeState : std::uint8_t { unchecked = 0, ok = 1, error = 2 };

std::vector<PointSpec> make_points();

}  // namespace drivegate::mdriver
