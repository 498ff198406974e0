// ED_OP_STATE (eDrive RS485 Interface V16, "Interpretation of consolidated data"): the operating
// state the Status payload reports, and what a state says about the motor and about a Set Run
// State the drive was sent. The driver confirms its writes by these (README.md, "Writes and their
// confirmation"); the fault mapping and the simulator read them too.
#pragma once

#include <cstdint>

#include "labels.h"

namespace drivegate::unicla {

// "the first entry is equal to 0".
enum class OpState : std::uint8_t {
  not_ready = 0,
  starting = 1,
  running = 2,
  stopped = 3,
  wait_compressor_safety = 4,
  wait_anti_short = 5,
  fault_compressor_safety = 6,
  fault_motor = 7,
  fault_fmc = 8,
  fault_electrical = 9,
  fault_configuration = 10,
  fault_xc_comms = 11,
  locked = 12,
  motor_thermal_inhibit = 13,
  oil_balance_running = 14,
  oil_balance_required = 15,
  oil_balance_run_wait = 16,
};
inline constexpr std::uint8_t kOpStateCount = 17;
static_assert(kOpStateNames.size() == kOpStateCount);

// Each takes the raw byte of the Status: a value past the document's list is a state the drive
// knows and drivegate does not.

// Fault - Compressor Safety .. Fault - XC Comms.
bool is_fault_state(std::uint8_t op_state);
// Starting, Running, Oil Balance Running: the motor turns or is about to.
bool is_running_state(std::uint8_t op_state);
// A state in which the drive will not take a run: Fault-*, Not Ready, Locked, Motor Thermal
// Inhibit, and any state the document does not list.
bool refuses_run(std::uint8_t op_state);
// A state that shows a stopped drive took a run: running, or waiting to (Wait - Compressor
// Safety, Wait - Anti Short, Oil Balance Required, Oil Balance Run Wait).
bool took_run(std::uint8_t op_state);

}  // namespace drivegate::unicla
