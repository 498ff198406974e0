// Enum and flag names as tabled in eDrive RS485 Interface V16, "Interpretation of consolidated
// data" and "Interpreting Safety Flags". Value / bit number = position, empty = "X" (unused).
#pragma once

#include <array>
#include <string_view>

namespace drivegate::unicla {

inline constexpr std::array<std::string_view, 6> kRefrigerantNames = {"Unknown", "R134A", "R1234YF",
                                                                      "R404A",   "R452A", "R513A"};
inline constexpr std::array<std::string_view, 6> kOilNames = {"Unknown", "PAG46", "PAG46HD",
                                                              "PAG56",   "POE32", "POE68"};
inline constexpr std::array<std::string_view, 5> kControlModeNames = {
    "eConnect", "Remote Enable", "Variable", "Variable + Remote Enable", "External Serial"};
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

// "Compressor Safety Flags - Run, Start"
inline constexpr std::array<std::string_view, 16> kCompressorFlagNames = {
    "",
    "",
    "",
    "",
    "Low Side Superheat High",
    "Low Side Superheat Low",
    "High Side Superheat High",
    "High Side Superheat Low",
    "Low Side Temperature High",
    "Low Side Temperature Low",
    "Low Side Pressure High",
    "Low Side Pressure Low",
    "High Side Temperature High",
    "High Side Temperature Low",
    "High Side Pressure High",
    "High Side Pressure Low"};

// "Motor Safety Flags - Run, Start"
inline constexpr std::array<std::string_view, 16> kMotorFlagNames = {
    "",
    "Switch Temperature Low",
    "Switch Temperature High",
    "Motor Temperature Low",
    "Motor Temperature High",
    "Motor Power Run Limit",
    "Motor Power Absolute Limit",
    "ST Motor Control Fault",
    "ST Motor Control - High FOC Rate",
    "ST Motor Control - Over voltage",
    "ST Motor Control - Under Voltage",
    "ST Motor Control - Over Temperature",
    "ST Motor Control - Startup Fail",
    "ST Motor Control - Speed Feedback Error",
    "ST Motor Control - Over Current",
    "ST Motor Control - Software Error"};

// "Electrical Safety Flags" (24 bits)
inline constexpr std::array<std::string_view, 24> kElectricalFlagNames = {"FMC Data Invalid",
                                                                          "FMC 3.3V Fault",
                                                                          "FMC 5.0V Fault",
                                                                          "FMC VMON 24V Low",
                                                                          "FMC VMON 24V High",
                                                                          "FMC VMON UDXC 24V Low",
                                                                          "FMC VMON UDXC 24V High",
                                                                          "FMC VMON UDXC 5V Low",
                                                                          "FMC VMON UDXC 5V High",
                                                                          "FMC CT 5V Low",
                                                                          "FMC CT 5V High",
                                                                          "",
                                                                          "",
                                                                          "",
                                                                          "",
                                                                          "",
                                                                          "CMC 3V3 Fault",
                                                                          "CMC 5V0 Fault",
                                                                          "CMC VMON 5V Low",
                                                                          "CMC VMON 5V High",
                                                                          "CMC AUX VMON VCC Low",
                                                                          "CMC AUX VMON VCC High",
                                                                          "CMC UDPC VCC Low",
                                                                          "CMC UDPC VCC High"};

}  // namespace drivegate::unicla
