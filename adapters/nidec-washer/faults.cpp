#include "faults.h"

#include <array>
#include <string_view>

namespace drivegate::nidec {
namespace {

struct FaultBit {
  std::uint8_t mask;
  std::string_view name;
  Fault fault;
};

// Section 8, FAULT TABLE (two rows share 0x04: DC bus > 500 V and bus over-voltage).
constexpr std::array<FaultBit, 8> kBits = {{
    {0x01, "general", Fault::internal_error},                       // micro class B fault
    {0x02, "ipm_over_temperature", Fault::drive_over_temperature},  // IPM >= 95 degC
    {0x04, "over_voltage", Fault::over_voltage},                    // DC bus > 500 V / >= 450 V
    {0x08, "stall", Fault::stall},                                  // motor stall or tacho missing
    {0x10, "over_current", Fault::over_current},                    // hardware over-current
    {0x20, "under_voltage", Fault::under_voltage},                  // DC bus <= 190 V
    {0x40, "phase_loss", Fault::phase_loss},                        // lost phase
    {0x80, "motor_over_temperature", Fault::motor_over_temperature},  // winding >= 140 degC
}};

constexpr bool in_bit_order() {
  for (std::size_t bit = 0; bit < kBits.size(); ++bit) {
    if (kBits[bit].mask != (1u << bit)) return false;
  }
  return true;
}
static_assert(in_bit_order(), "fault_bit_labels() labels bit n with entry n");

}  // namespace

FaultSet map_faults(std::uint8_t error_bits) {
  FaultSet set;
  for (const FaultBit& b : kBits) {
    if ((error_bits & b.mask) != 0) set.set(b.fault);
  }
  return set;
}

std::vector<Label> fault_bit_labels() {
  // kBits is in bit order (entry n is mask 1 << n), so the names label bits 0..7 in order.
  std::array<std::string_view, kBits.size()> names{};
  for (std::size_t bit = 0; bit < kBits.size(); ++bit) names[bit] = kBits[bit].name;
  return labels_in_order(names);
}

std::optional<std::uint8_t> fault_mask(std::string_view name) {
  for (const FaultBit& b : kBits) {
    if (b.name == name) return b.mask;
  }
  return std::nullopt;
}

std::string fault_names() {
  std::string out;
  for (const FaultBit& b : kBits) {
    if (!out.empty()) out += '|';
    out += b.name;
  }
  return out;
}

}  // namespace drivegate::nidec
