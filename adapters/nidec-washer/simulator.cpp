#include "simulator.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "drivegate/bytes.h"
#include "drivegate/sim_rx.h"

namespace drivegate::nidec {
namespace {

constexpr Millis kBusSilence{6000};  // section 7: no bus activity for 6 s stops the motor
constexpr Millis kFrameGap{50};      // not in the document: a pause this long drops a partial frame
constexpr Millis kFaultClear{4000};  // section 8: most faults clear after 4 s
constexpr Millis kMotorTempClear{20000};  // section 8, 0x80: 20 s
constexpr Millis kWeighing{35000};        // 5.10: weight detection completes in about 35 s
constexpr double kStopRamp = 1000.0;      // rpm/s, closed-loop stop (5.7): the simulator's choice
constexpr double kBrakeRamp = 5000.0;     // rpm/s, brake (5.8): faster than stop
constexpr std::uint16_t kIpmTemperature = 45;  // FCT (5.15) reading, simulator's choice
constexpr std::uint8_t kIpmModel = 1;          // FCT byte 9 high nibble, simulator's choice

double seconds(Millis m) {
  return static_cast<double>(m.count()) / 1000.0;
}

}  // namespace

Bytes NidecWasherSimulator::send(Bytes frame) {
  if (corrupt_ > 0) {
    --corrupt_;
    frame.back() ^= 0xFF;
  }
  return frame;
}

Bytes NidecWasherSimulator::on_receive(ByteView rx, TimePoint now) {
  if (silent_) return {};  // "silent on": as if unplugged, it neither hears nor answers
  advance(now);
  if (!rx_.empty() && last_byte_ && now - *last_byte_ > kFrameGap) rx_.clear();
  if (!rx.empty()) {
    last_byte_ = now;
    comm_fault_ = false;
  }
  rx_.insert(rx_.end(), rx.begin(), rx.end());
  Bytes out;
  while (const auto d = take_decoded(rx_, [](ByteView b) { return decode_request(b); })) {
    if (d->status == DecodeStatus::bad && d->error == make_error_code(FrameError::bad_header)) {
      continue;  // not a frame start: skip to the next A5
    }
    Bytes reply;
    if (d->status == DecodeStatus::bad || nack_ > 0) {
      // 5.16: a wrong checksum, or a mode V07 does not know (0x19 included), gets a NACK.
      if (d->status == DecodeStatus::frame) --nack_;
      ++nacks_sent_;
      reply = send(encode_nack());
    } else {
      ++frames_;
      reply = send(handle(d->frame, now));
    }
    out.insert(out.end(), reply.begin(), reply.end());
  }
  return out;
}

Bytes NidecWasherSimulator::status_reply(Mode m, std::uint8_t last) const {
  const std::uint16_t s = speed();
  return encode_reply(m, {faults_, hi8(s), lo8(s), last});
}

Bytes NidecWasherSimulator::handle(const Request& r, TimePoint now) {
  const auto& d = r.data;
  switch (r.mode) {
    case Mode::ping:  // 5.1
      pinged_ = true;
      platform_ = d[0];
      empty_raw_ = be16(d[1], d[2]);
      return encode_reply(Mode::ping, {platform_, hi8(version_), lo8(version_), 0});
    case Mode::request:
      return status_reply(Mode::request, weight());  // 5.2
    case Mode::cw:                                   // 5.3
    case Mode::ccw:                                  // 5.4
    case Mode::agitation:                            // 5.5
    case Mode::spin:                                 // 5.6
    case Mode::free_shaft_spin:                      // 5.14
      start(rotation(r.mode), r, now);
      return status_reply(r.mode);
    case Mode::stop:  // 5.7
      if (motion_ != Motion::stopped) motion_ = Motion::stopping;
      return status_reply(r.mode);
    case Mode::brake:  // 5.8
      if (motion_ != Motion::stopped) motion_ = Motion::braking;
      return status_reply(r.mode);
    case Mode::forced_brake:  // 5.13
      forced_brake_ = d[0] == 1;
      if (forced_brake_) {
        motion_ = Motion::stopped;
        speed_ = 0.0;
      }
      return status_reply(r.mode, forced_brake_ ? 1 : 0);
    case Mode::voltage_detection:  // 5.9
      return encode_reply(r.mode, {faults_, hi8(dc_bus_), lo8(dc_bus_), 0});
    case Mode::weight_detection: {  // 5.10
      if (!weighing_since_ && !weighed_) weighing_since_ = now;
      const std::uint16_t raw = raw_weight();
      return encode_reply(r.mode, {faults_, hi8(raw), lo8(raw), weight()});
    }
    case Mode::fabric_detection:  // 5.11: layout unknown; error, result byte, 00, 00
      return encode_reply(r.mode, {faults_, fabric_, 0, 0});
    case Mode::fct_test: {  // 5.15
      const std::uint16_t s = speed();
      const std::uint16_t current = s == 0 ? 0 : 150;
      const auto model_bus = static_cast<std::uint8_t>((kIpmModel << 4) | (hi8(dc_bus_) & 0x0F));
      return encode_fct_reply({0, faults_, hi8(s), lo8(s), hi8(kIpmTemperature),
                               lo8(kIpmTemperature), model_bus, lo8(dc_bus_), hi8(current),
                               lo8(current)});
    }
  }
  return encode_nack();
}

// The motion a rotation mode starts, of the same name.
NidecWasherSimulator::Motion NidecWasherSimulator::rotation(Mode m) {
  constexpr std::array<std::pair<Mode, Motion>, 5> kRotations = {{
      {Mode::cw, Motion::cw},
      {Mode::ccw, Motion::ccw},
      {Mode::agitation, Motion::agitation},
      {Mode::spin, Motion::spin},
      {Mode::free_shaft_spin, Motion::free_shaft_spin},
  }};
  for (const auto& [mode, motion] : kRotations) {
    if (mode == m) return motion;
  }
  return Motion::stopped;
}

void NidecWasherSimulator::start(Motion m, const Request& r, TimePoint now) {
  // 5.1: no motion before the ping; section 8: none while a fault is reported; 5.13: none
  // while the forced brake holds. The ACK still goes out (with the Error bits).
  if (!pinged_ || faults_ != 0 || forced_brake_) return;
  motion_ = m;
  target_ = be16(r.data[0], r.data[1]);
  phase_start_ = now;
  double accel_s = 0.0;
  if (m == Motion::agitation) {
    agitation_ = {r.data[2], r.data[3], r.data[4], r.data[5], r.data[6], r.data[7]};
    accel_s = agitation_.accel / 10.0;
  } else {
    accel_s = be16(r.data[2], r.data[3]) / 10.0;  // 5.3: x 100 ms
  }
  ramp_ = accel_s > 0.0 ? std::max<double>(target_, 1.0) / accel_s : 1e9;
}

void NidecWasherSimulator::trip(std::uint8_t bits, TimePoint now) {
  faults_ |= bits;
  for (std::size_t bit = 0; bit < 8; ++bit) {
    const auto mask = static_cast<std::uint8_t>(1u << bit);
    if ((bits & mask) == 0) continue;
    if (mask == 0x01) {
      clear_at_[bit].reset();  // section 8: general fault is kept until power off
    } else {
      clear_at_[bit] = now + (mask == 0x80 ? kMotorTempClear : kFaultClear);
    }
  }
  motion_ = Motion::stopped;  // section 8: every fault stops the motor to zero speed
  speed_ = 0.0;
}

void NidecWasherSimulator::advance(TimePoint now) {
  const double dt =
      last_tick_ ? seconds(std::chrono::duration_cast<Millis>(now - *last_tick_)) : 0.0;
  last_tick_ = now;
  for (std::size_t bit = 0; bit < 8; ++bit) {
    if (clear_at_[bit] && now >= *clear_at_[bit]) {
      faults_ &= static_cast<std::uint8_t>(~(1u << bit));
      clear_at_[bit].reset();
    }
  }
  if (weighing_since_ && now - *weighing_since_ >= kWeighing) {
    weighing_since_.reset();
    weighed_ = true;
  }
  if (last_byte_ && now - *last_byte_ > kBusSilence && !comm_fault_) {
    // Section 7: the inverter stops the motor; it then wants a new ping (5.1) before motion.
    comm_fault_ = true;
    motion_ = Motion::stopped;
    speed_ = 0.0;
    pinged_ = false;
  }
  switch (motion_) {
    case Motion::stopped:
      speed_ = 0.0;
      break;
    case Motion::stopping:
    case Motion::braking:
      speed_ = std::max(0.0, speed_ - (motion_ == Motion::braking ? kBrakeRamp : kStopRamp) * dt);
      if (speed_ == 0.0) motion_ = Motion::stopped;
      break;
    case Motion::agitation: {
      // 5.5: CW on, CW off, CCW on, CCW off, repeated; the speed reads 0 while off.
      const long on_cw = agitation_.cw_on * 100L, off_cw = agitation_.cw_off * 100L;
      const long on_ccw = agitation_.ccw_on * 100L, off_ccw = agitation_.ccw_off * 100L;
      const long cycle = on_cw + off_cw + on_ccw + off_ccw;
      const long t =
          cycle == 0 ? 0 : std::chrono::duration_cast<Millis>(now - phase_start_).count() % cycle;
      const bool on =
          cycle == 0 || t < on_cw || (t >= on_cw + off_cw && t < on_cw + off_cw + on_ccw);
      speed_ = on ? target_ : 0.0;
      break;
    }
    default:
      if (speed_ < target_) speed_ = std::min<double>(target_, speed_ + ramp_ * dt);
      if (speed_ > target_) speed_ = std::max<double>(target_, speed_ - ramp_ * dt);
      break;
  }
}

Bytes NidecWasherSimulator::on_tick(TimePoint now) {
  advance(now);
  return {};  // section 2: the inverter never speaks unasked
}

std::uint16_t NidecWasherSimulator::speed() const {
  return static_cast<std::uint16_t>(std::lround(std::clamp(speed_, 0.0, 65535.0)));
}

std::uint8_t NidecWasherSimulator::weight() const {
  return weighed_ ? load_ : 0;
}  // 5.2: 0 = none

std::uint16_t NidecWasherSimulator::raw_weight() const {
  // 5.10: the simulator's own raw table: 1000 empty, +20 per 100 g; 0 until detected.
  return weighed_ ? static_cast<std::uint16_t>(1000 + 20 * load_) : 0;
}

}  // namespace drivegate::nidec
