// The names of the values the payloads carry as numbers (eDrive RS485 Interface V16,
// "Interpretation of consolidated data"), in the document's order: "the first entry is equal to
// 0". The safety flags' names are with their fault mapping (faults.h).
#pragma once

#include <array>
#include <string_view>

namespace drivegate::unicla {

// ED_REFRIGERANTS (Build Information, Refrigerant).
inline constexpr std::array<std::string_view, 6> kRefrigerantNames = {"Unknown", "R134A", "R1234YF",
                                                                      "R404A",   "R452A", "R513A"};
// ED_OILS (Build Information, Oil).
inline constexpr std::array<std::string_view, 6> kOilNames = {"Unknown", "PAG46", "PAG46HD",
                                                              "PAG56",   "POE32", "POE68"};
// ED_CONTROL_MODE (Status, Control Mode).
inline constexpr std::array<std::string_view, 5> kControlModeNames = {
    "eConnect", "Remote Enable", "Variable", "Variable + Remote Enable", "External Serial"};
// ED_OP_STATE (Status, Status); op_state.h says what each state means.
inline constexpr std::array<std::string_view, 17> kOpStateNames = {"Not Ready",
                                                                   "Starting",
                                                                   "Running",
                                                                   "Stopped",
                                                                   "Wait - Compressor Safety",
                                                                   "Wait - Anti Short",
                                                                   "Fault - Compressor Safety",
                                                                   "Fault - Motor",
                                                                   "Fault - FMC",
                                                                   "Fault - Electrical",
                                                                   "Fault - Configuration",
                                                                   "Fault - XC Comms",
                                                                   "Locked",
                                                                   "Motor Thermal Inhibit",
                                                                   "Oil Balance Running",
                                                                   "Oil Balance Required",
                                                                   "Oil Balance Run Wait"};

}  // namespace drivegate::unicla
