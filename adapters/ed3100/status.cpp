// How the driver reads the drive's state: the 0x0E01 fault/state pair and the monitors
// (vendor document, "Read fault code" and "read monitoring parameters").
#include <algorithm>
#include <cmath>

#include "driver.h"
#include "points.h"

namespace drivegate::ed3100 {
namespace {

// Monitor format bits 0..4 give the decimals: bit0 one negative decimal (x10), bit1 none,
// bit2 one, bit3 two, bit4 three (shared/specs/README.md, "ed3100"). None set: unscaled.
double format_scale(std::uint16_t fmt) {
  constexpr double kScales[] = {10.0, 1.0, 0.1, 0.01, 0.001};
  for (unsigned b = kFmtDecimalsMinus1; b <= kFmtDecimals3; ++b) {
    if (bit(fmt, b)) return kScales[b];
  }
  return 1.0;
}

}  // namespace

void Ed3100Driver::apply_fault(const std::vector<std::uint16_t>& w) {
  fault_word_ = w.at(0);
  state_word_ = w.at(1);
  auto flag = [&](unsigned b) { return static_cast<std::int64_t>(bit(state_word_, b)); };
  values_[index(Fixed::fault_code)] = static_cast<std::int64_t>(fault_word_);
  values_[index(Fixed::state_word)] = static_cast<std::int64_t>(state_word_);
  values_[index(Fixed::running)] = flag(kStRunning);
  values_[index(Fixed::direction)] = flag(kStRunReverse);
  values_[index(Fixed::commanded_direction)] = flag(kStCmdReverse);
  values_[index(Fixed::accelerating)] = flag(kStAccelerating);
  values_[index(Fixed::decelerating)] = flag(kStDecelerating);
  common_.running = bit(state_word_, kStRunning);
  // The fault code table is not legible in the document (shared/specs/README.md): every code
  // is unified as `other`, the raw code goes to native_fault.
  common_.faults = FaultSet{};
  common_.native_fault = 0;
  if (fault_word_ != kNoFault) {
    common_.faults.set(Fault::other);
    common_.native_fault = fault_word_;
  }
  update_speed();
}

void Ed3100Driver::apply_monitor(std::size_t slot, const std::vector<std::uint16_t>& w) {
  const std::uint16_t raw = w.at(0);
  const std::uint16_t fmt = w.at(1);
  const double value = raw * format_scale(fmt);
  const std::size_t base = monitor_value_index(slot);
  values_[base] = value;
  values_[base + 1] = static_cast<std::int64_t>(raw);
  values_[base + 2] = static_cast<std::int64_t>(fmt);
  if (slot == config_.speed_monitor) {
    speed_hz_ = value;
    speed_stopped_ = bit(fmt, kFmtStopped);
    update_speed();
  }
}

void Ed3100Driver::update_speed() {
  if (!speed_hz_) return;
  // Stopped, the monitor shows the reference rather than the output (document example:
  // 42.28 Hz with the stopped bit): the motor does not turn.
  const bool turning = !speed_stopped_ && (!fault_known_ || bit(state_word_, kStRunning));
  std::int32_t rpm = turning ? rpm_from_hz(*speed_hz_) : 0;
  if (bit(state_word_, kStRunReverse)) rpm = -rpm;
  common_.speed_rpm = rpm;
}

void Ed3100Driver::update_ready() {
  common_.ready = fault_known_ &&
                  std::all_of(param_known_.begin(), param_known_.end(), [](bool b) { return b; });
}

}  // namespace drivegate::ed3100
