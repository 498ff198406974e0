// NidecWasherDriver: what each ACK of section 5 tells about the drive.
#include "driver.h"
#include "faults.h"

namespace drivegate::nidec {

void NidecWasherDriver::apply_error(std::uint8_t error) {
  common_.native_fault = error;
  common_.faults = map_faults(error);
  values_[pt::error_bits] = std::int64_t{error};
  // Section 8: every fault stops the motor to zero speed, so no run is in force any more.
  if (error != 0 && is_run(common_.command)) set_command(Command::stop);
}

void NidecWasherDriver::apply_speed(std::uint16_t rpm) {
  common_.speed_rpm = rpm;  // the protocol has no sign: CCW reads positive too
}

void NidecWasherDriver::apply_reply(const Reply& r) {
  switch (r.mode) {
    case Mode::ping:  // 5.1: platform, version high, low, 00
      values_[pt::platform] = std::int64_t{r.data[0]};
      values_[pt::inverter_version] = std::int64_t{r.u16(1)};
      return;
    case Mode::request:  // 5.2: error, speed high, low, weight (x 100 g)
      apply_error(r.error());
      apply_speed(r.u16(1));
      values_[pt::weight] = static_cast<double>(r.data[3]) / 10.0;
      return;
    case Mode::cw:               // 5.3
    case Mode::ccw:              // 5.4
    case Mode::agitation:        // 5.5
    case Mode::spin:             // 5.6
    case Mode::stop:             // 5.7
    case Mode::brake:            // 5.8
    case Mode::free_shaft_spin:  // 5.14: error, speed high, low, 00
      apply_error(r.error());
      apply_speed(r.u16(1));
      return;
    case Mode::forced_brake:  // 5.13: error, speed high, low, 1 enabled / 0 disabled
      apply_error(r.error());
      apply_speed(r.u16(1));
      forced_brake_ = r.data[3] != 0;
      values_[pt::forced_brake] = std::int64_t{forced_brake_ ? 1 : 0};
      // 5.13: the forced brake stops the motor "in any situation" and holds it: no run is in
      // force while it is enabled.
      if (forced_brake_ && is_run(common_.command)) set_command(Command::stop);
      return;
    case Mode::voltage_detection:  // 5.9: error, DC bus high, low, 00
      apply_error(r.error());
      values_[pt::dc_bus_voltage] = std::int64_t{r.u16(1)};
      return;
    case Mode::weight_detection:  // 5.10: error, raw weight high, low, weight (x 100 g)
      apply_error(r.error());
      values_[pt::raw_weight] = std::int64_t{r.u16(1)};
      values_[pt::weight] = static_cast<double>(r.data[3]) / 10.0;
      return;
    case Mode::fabric_detection: {  // 5.11: no layout in the document: kept raw
      const std::uint32_t raw = (std::uint32_t{r.u16(0)} << 16) | r.u16(2);
      values_[pt::fabric_raw] = std::int64_t{raw};
      return;
    }
    case Mode::fct_test:  // 5.15: 10 data bytes; its 16-bit Error is not the section 8 byte
      values_[pt::fct_error] = std::int64_t{r.u16(0)};
      values_[pt::fct_speed_rpm] = std::int64_t{r.u16(2)};
      values_[pt::fct_ipm_temperature] = std::int64_t{r.u16(4)};
      values_[pt::fct_ipm_model_bus_volt_high] = std::int64_t{r.data[6]};
      values_[pt::fct_bus_volt_low] = std::int64_t{r.data[7]};
      values_[pt::fct_phase_current] = std::int64_t{r.u16(8)};
      return;
  }
}

}  // namespace drivegate::nidec
