#include "op_state.h"

namespace drivegate::unicla {

namespace {
OpState state(std::uint8_t s) {
  return static_cast<OpState>(s);
}
}  // namespace

bool is_fault_state(std::uint8_t s) {
  return s >= static_cast<std::uint8_t>(OpState::fault_compressor_safety) &&
         s <= static_cast<std::uint8_t>(OpState::fault_xc_comms);
}

bool is_running_state(std::uint8_t s) {
  const OpState st = state(s);
  return st == OpState::starting || st == OpState::running || st == OpState::oil_balance_running;
}

bool refuses_run(std::uint8_t s) {
  const OpState st = state(s);
  return is_fault_state(s) || st == OpState::not_ready || st == OpState::locked ||
         st == OpState::motor_thermal_inhibit || s >= kOpStateCount;
}

bool took_run(std::uint8_t s) {
  const OpState st = state(s);
  return is_running_state(s) || st == OpState::wait_compressor_safety ||
         st == OpState::wait_anti_short || st == OpState::oil_balance_required ||
         st == OpState::oil_balance_run_wait;
}

}  // namespace drivegate::unicla
