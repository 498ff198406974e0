// The adapter's own points (after the common block). The programming points exist only when
// the driver may write non-volatile memory (maintenance, or allow_nv_programming).
#pragma once

#include <cstddef>
#include <vector>

#include "drivegate/point.h"

namespace drivegate::fdc1 {

namespace pt {
// Always present: the streamed status.
inline constexpr std::size_t motor_on = 0;
inline constexpr std::size_t current_a = 1;
inline constexpr std::size_t restart_s = 2;
inline constexpr std::size_t alarm_code = 3;
inline constexpr std::size_t alarm_latched = 4;
inline constexpr std::size_t sent_speed_rpm = 5;
inline constexpr std::size_t status_count = 6;
// Programming (non-volatile memory).
inline constexpr std::size_t prog_min_rpm = 6;
inline constexpr std::size_t prog_max_rpm = 7;
inline constexpr std::size_t prog_mode = 8;
inline constexpr std::size_t prog_cut_out_12v = 9;
inline constexpr std::size_t prog_cut_in_12v = 10;
inline constexpr std::size_t prog_cut_out_24v = 11;
inline constexpr std::size_t prog_cut_in_24v = 12;
inline constexpr std::size_t prog_cut_out_42v = 13;
inline constexpr std::size_t prog_cut_in_42v = 14;
inline constexpr std::size_t prog_cut_out_special = 15;
inline constexpr std::size_t prog_cut_in_special = 16;
inline constexpr std::size_t prog_nominal_v = 17;
inline constexpr std::size_t prog_commit = 18;
inline constexpr std::size_t prog_status = 19;
inline constexpr std::size_t prog_message = 20;
inline constexpr std::size_t all_count = 21;
}  // namespace pt

// Values of prog_status.
enum class ProgStatus : std::int64_t { idle = 0, pending, ok, refused, no_response, invalid };

std::vector<PointSpec> make_points(bool programming);

}  // namespace drivegate::fdc1
