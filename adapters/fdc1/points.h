// The adapter's own points (after the common block): the streamed status, and the programming of
// the non-volatile settings, which exists only when the driver may write them (maintenance, or
// allow_nv_programming). The programming points are the parameters of the maintenance action
// `program` (plugin.cpp): `drivegate action ... program KEY=VALUE` writes prog_KEY for each key,
// then 1 to prog_commit, and prints prog_message when it fails.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "drivegate/point.h"

namespace drivegate::fdc1 {

// Index of each point in points() / values().
namespace pt {
// The streamed status (OUTPUT): always present.
inline constexpr std::size_t motor_on = 0;
inline constexpr std::size_t current_a = 1;
inline constexpr std::size_t restart_s = 2;
inline constexpr std::size_t alarm_code = 3;
inline constexpr std::size_t alarm_latched = 4;
inline constexpr std::size_t sent_speed_rpm = 5;
// Programming (INPUT, "Programming mode + parameters"): points() ends before prog_min_rpm
// without it. prog_min_rpm..prog_nominal_v are the frame's fields, in this order.
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
inline constexpr std::size_t count = 21;
}  // namespace pt

// The maintenance action's names (AdapterDescriptor::actions): the prefix of its parameters, the
// point that carries it out, and the one that says why it failed.
inline constexpr const char* kProgramAction = "program";
inline constexpr const char* kProgramPrefix = "prog_";
inline constexpr const char* kCommitPoint = "prog_commit";
inline constexpr const char* kMessagePoint = "prog_message";

// Values of prog_status.
enum class ProgStatus : std::uint8_t { idle = 0, pending, ok, refused, no_response, invalid };
inline constexpr std::array<std::string_view, 6> kProgStatusNames = {
    "idle", "pending", "ok", "refused", "no_response", "invalid"};

// Whether `index` is one of the frame's fields (a parameter of the action).
constexpr bool is_program_field(std::size_t index) {
  return index >= pt::prog_min_rpm && index <= pt::prog_nominal_v;
}
// The voltage fields, stored as volts; the others (rpm, mode byte) as whole numbers.
constexpr bool is_volts_field(std::size_t index) {
  return index >= pt::prog_cut_out_12v && index <= pt::prog_nominal_v;
}

std::vector<PointSpec> make_points(bool programming);

}  // namespace drivegate::fdc1
