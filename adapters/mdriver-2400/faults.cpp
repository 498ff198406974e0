#include "faults.h"

#include <array>

namespace drivegate::mdriver {
namespace {

// Vendor document, モータドライバ エラーコード; unified faults as the adapter's README assigns them.
constexpr std::array<ErrorCodeInfo, 14> kErrors = {{
    {0x01, "dc_over_voltage", "inverter DC over-voltage", Fault::over_voltage},
    {0x02, "dc_under_voltage", "inverter DC under-voltage", Fault::under_voltage},
    {0x03, "ac_over_current", "inverter AC over-current", Fault::over_current},
    {0x04, "stall", "speed estimate under limit (loss of synchronism)", Fault::stall},
    {0x05, "phase_loss_1", "phase loss 1 (speed estimate pulsation)", Fault::phase_loss},
    {0x06, "phase_loss_2", "phase loss 2 (current imbalance)", Fault::phase_loss},
    {0x07, "ipm_error_1", "IPM error 1 (edge detection)", Fault::hardware_fault},
    {0x08, "ipm_error_2", "IPM error 2 (level detection)", Fault::hardware_fault},
    {0x09, "current_sensor", "current sensor fault", Fault::sensor_fault},
    {0x0A, "reserved", "(reserved)", Fault::other},
    {0x0B, "pwm_terminal", "inverter PWM terminal fault", Fault::hardware_fault},
    {0x0C, "comm_error", "communication error: no frame from the master for 6 s, stopped",
     Fault::comm_lost},
    {0x0D, "mode_setting", "COM/Duty mode setting fault", Fault::config_error},
    {0x0E, "ipm_over_temperature", "IPM over-temperature", Fault::drive_over_temperature},
}};

// The table runs 0x01..0x0E without a gap, so its names in order label the codes.
constexpr bool codes_in_order() {
  for (std::size_t i = 0; i < kErrors.size(); ++i) {
    if (kErrors[i].code != i + 1) return false;
  }
  return true;
}
static_assert(codes_in_order());

}  // namespace

std::span<const ErrorCodeInfo> error_codes() {
  return kErrors;
}

std::optional<ErrorCodeInfo> find_error(std::uint8_t code) {
  for (const auto& e : kErrors)
    if (e.code == code) return e;
  return std::nullopt;
}

std::optional<ErrorCodeInfo> find_error(std::string_view name) {
  for (const auto& e : kErrors)
    if (e.name == name) return e;
  return std::nullopt;
}

Fault fault_of(std::uint8_t code) {
  if (code == 0) return Fault::none;
  const auto e = find_error(code);
  return e ? e->fault : Fault::other;
}

std::vector<Label> error_code_labels() {
  std::vector<std::string_view> names{"none"};  // 0x00: 異常なし
  for (const auto& e : kErrors) names.push_back(e.name);
  return labels_in_order(names);
}

}  // namespace drivegate::mdriver
