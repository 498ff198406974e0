// The ED3100 register map as the document prints it (vendor document, sections "communication
// protocol defines the parameters of the word address", "Start forward command ...", "read
// monitoring parameters", "Read fault code"), with shared/specs/README.md section "ed3100".
#pragma once

#include <cstdint>

namespace drivegate::ed3100 {

// Drive command word (examples "Start forward command", "Reverse run command", "Written stop
// order").
inline constexpr std::uint16_t kRegCommand = 0x2000;
inline constexpr std::uint16_t kCmdForward = 0x001E;         // forward, continuous
inline constexpr std::uint16_t kCmdForwardOneShot = 0x0012;  // forward, one time run
inline constexpr std::uint16_t kCmdReverse = 0x002E;         // reverse, continuous
inline constexpr std::uint16_t kCmdStop = 0x0001;
// Frequency reference in 0.01 Hz (README: 0x1388 = 50.00 Hz).
inline constexpr std::uint16_t kRegFrequency = 0x2001;
// Fault reset: the document names none. The command word's bits follow the common 0x2000
// layout (bits 0-1 01 stop / 10 run, bits 4-5 01 forward / 10 reverse), whose family resets
// faults with bit 1 of 0x2002; drivegate's choice, configurable (README.md of this adapter).
inline constexpr std::uint16_t kRegResetDefault = 0x2002;
inline constexpr std::uint16_t kResetValueDefault = 0x0002;

// Monitor values 0x0D00..0x0D28, two words each: value, format (document, "read monitoring
// parameters"; "reading invalid address more than 0D28").
inline constexpr std::uint16_t kRegMonitorFirst = 0x0D00;
inline constexpr std::uint16_t kRegMonitorLast = 0x0D28;
inline constexpr std::uint16_t kMonitorWords = 2;
// Format word bits (document, "B0 ~ B3 Parameters"; README: bit0 = one negative decimal,
// bits 1-4 = 0..3 decimals).
inline constexpr unsigned kFmtDecimalsMinus1 = 0;
inline constexpr unsigned kFmtDecimals0 = 1;
inline constexpr unsigned kFmtDecimals1 = 2;
inline constexpr unsigned kFmtDecimals2 = 3;
inline constexpr unsigned kFmtDecimals3 = 4;
inline constexpr unsigned kFmtVolt = 5;
inline constexpr unsigned kFmtHertz = 6;
inline constexpr unsigned kFmtAmpere = 7;
inline constexpr unsigned kFmtNormal = 8;
inline constexpr unsigned kFmtInputTerminals = 12;
inline constexpr unsigned kFmtFault = 13;
inline constexpr unsigned kFmtStopped = 14;

// Fault and state (document, "Read fault code"; "B4 ~ B7 Parameters").
inline constexpr std::uint16_t kRegFault = 0x0E01;
inline constexpr std::uint16_t kFaultWords = 2;
inline constexpr std::uint16_t kNoFault = 0xFFFF;  // word 1 when no fault occurs
inline constexpr unsigned kStRunReverse = 1;       // running direction, 1 = reverse
inline constexpr unsigned kStPhaseReverse = 2;     // output phase order, 1 = reverse
inline constexpr unsigned kStCmdReverse = 3;       // commanded direction, 1 = reverse
inline constexpr unsigned kStRunning = 4;          // "Operation"
inline constexpr unsigned kStFault = 5;            // "Failure"
inline constexpr unsigned kStDigitalChannel = 6;   // frequency channel 0 (digital setting)
inline constexpr unsigned kStAccelerating = 10;
inline constexpr unsigned kStDecelerating = 11;

// Parameters GG-nn live at 0xGGnn (document, "Setting parameters GGnnH": 04-01 is 0x0401).
// Groups stop below the monitor block at 0x0D.
inline constexpr std::uint8_t kParamGroupMax = 0x0C;

// The document's monitor and fault reads carry 00 00 where the quantity belongs ("retained
// data ... does not affect the results"): the driver sends them as printed.
inline constexpr std::uint16_t kRetainedCount = 0x0000;

constexpr bool bit(std::uint16_t word, unsigned n) {
  return ((word >> n) & 1u) != 0;
}

// The factor a monitor's value is read with: the lowest of format bits 0..4 that is set gives
// the decimals, bit 0 one negative decimal (x10), bit 1 none, bit 2 one, bit 3 two, bit 4 three
// (shared/specs/README.md, "ed3100"). None set: unscaled.
constexpr double format_scale(std::uint16_t format) {
  constexpr double kScales[] = {10.0, 1.0, 0.1, 0.01, 0.001};
  for (unsigned b = kFmtDecimalsMinus1; b <= kFmtDecimals3; ++b) {
    if (bit(format, b)) return kScales[b];
  }
  return 1.0;
}

}  // namespace drivegate::ed3100
