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
enum : std::size_t {
  motor_on,
  current_a,
  restart_s,
  alarm_code,
  alarm_latched,
  sent_speed_rpm,
  // Programming (INPUT, "Programming mode + parameters"): points() ends before prog_min_rpm
  // without it. prog_min_rpm..prog_nominal_v are the frame's fields, in this order.
  prog_min_rpm,
  prog_max_rpm,
  prog_mode,
  prog_cut_out_12v,
  prog_cut_in_12v,
  prog_cut_out_24v,
  prog_cut_in_24v,
  prog_cut_out_42v,
  prog_cut_in_42v,
  prog_cut_out_special,
  prog_cut_in_special,
  prog_nominal_v,
  prog_commit,
  prog_status,
  prog_message,
  count,
};
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
