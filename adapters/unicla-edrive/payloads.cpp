#include "payloads.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <utility>

namespace drivegate::unicla {

namespace {

// Reads fields at fixed offsets of a payload.
class Reader {
 public:
  Reader(ByteView p, ByteOrder order) : p_(p), order_(order) {}
  std::uint8_t u8(std::size_t at) const { return p_[at]; }
  std::uint16_t u16(std::size_t at) const { return be16(p_[at], p_[at + 1]); }
  std::uint32_t u24(std::size_t at) const {
    return (std::uint32_t{p_[at]} << 16) | (std::uint32_t{p_[at + 1]} << 8) | p_[at + 2];
  }
  float f32(std::size_t at) const {
    std::uint32_t raw = 0;
    for (std::size_t i = 0; i < 4; ++i) {
      const std::size_t k = order_ == ByteOrder::big ? i : 3 - i;
      raw = (raw << 8) | p_[at + k];
    }
    return std::bit_cast<float>(raw);
  }
  Range range(std::size_t at) const { return {f32(at), f32(at + 4)}; }
  std::string ascii(std::size_t at, std::size_t n) const {
    std::string s(reinterpret_cast<const char*>(p_.data() + at), n);
    // Fields are padded: drivegate cuts at the first NUL and drops trailing spaces.
    if (const auto nul = s.find('\0'); nul != std::string::npos) s.resize(nul);
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
  }

 private:
  ByteView p_;
  ByteOrder order_;
};

// Writes fields at fixed offsets of a zero-filled payload.
class Writer {
 public:
  Writer(std::size_t size, ByteOrder order) : p_(size, 0), order_(order) {}
  void u8(std::size_t at, std::uint8_t v) { p_[at] = v; }
  void u16(std::size_t at, std::uint16_t v) {
    p_[at] = hi8(v);
    p_[at + 1] = lo8(v);
  }
  void u24(std::size_t at, std::uint32_t v) {
    p_[at] = static_cast<std::uint8_t>(v >> 16);
    p_[at + 1] = static_cast<std::uint8_t>(v >> 8);
    p_[at + 2] = static_cast<std::uint8_t>(v);
  }
  void f32(std::size_t at, float v) {
    const auto raw = std::bit_cast<std::uint32_t>(v);
    for (std::size_t i = 0; i < 4; ++i) {
      const std::size_t k = order_ == ByteOrder::big ? i : 3 - i;
      p_[at + k] = static_cast<std::uint8_t>(raw >> (24 - 8 * i));
    }
  }
  void range(std::size_t at, Range r) {
    f32(at, r.low);
    f32(at + 4, r.high);
  }
  void ascii(std::size_t at, std::size_t n, const std::string& s) {
    std::memcpy(p_.data() + at, s.data(), std::min(n, s.size()));
  }
  Bytes take() { return std::move(p_); }

 private:
  Bytes p_;
  ByteOrder order_;
};

// Row offsets ("Status" table: one row of 8 bytes per line).
namespace st {
constexpr std::size_t pressure = 0, temperature = 8, superheat = 16, motor = 24, state = 32,
                      motor_temps = 40, safety1 = 48, safety2 = 56;
}
// "Build Information" rows.
namespace bi {
constexpr std::size_t model = 0, serial = 16, compressor = 32, electrical = 40, name = 48;
}
// "Running Limits/ RS485 Config" rows.
namespace rl {
constexpr std::size_t speed = 0, suction_p = 8, discharge_p = 16, suction_t = 24, discharge_t = 32,
                      suction_sh = 40, discharge_sh = 48, rs485 = 56;
}

}  // namespace

std::optional<Status> parse_status(ByteView p, ByteOrder order) {
  if (p.size() < kStatusSize) return std::nullopt;
  const Reader r(p, order);
  Status s;
  s.suction_pressure = r.f32(st::pressure);
  s.discharge_pressure = r.f32(st::pressure + 4);
  s.suction_temperature = r.f32(st::temperature);
  s.discharge_temperature = r.f32(st::temperature + 4);
  s.suction_superheat = r.f32(st::superheat);
  s.discharge_superheat = r.f32(st::superheat + 4);
  s.rpm = r.u16(st::motor);
  s.volts = r.u16(st::motor + 2);
  s.watts = r.u16(st::motor + 4);
  s.torque = r.u16(st::motor + 6);
  s.op_state = r.u8(st::state);
  s.control_mode = r.u8(st::state + 1);
  s.demand = r.u8(st::state + 2);
  s.remote_enable = r.u8(st::state + 3);
  s.anti_short = r.u8(st::state + 4);
  s.motor_temperature = r.f32(st::motor_temps);
  s.switch_temperature = r.f32(st::motor_temps + 4);
  s.compressor_run_flags = r.u16(st::safety1);
  s.compressor_start_flags = r.u16(st::safety1 + 2);
  s.motor_run_flags = r.u16(st::safety1 + 4);
  s.motor_start_flags = r.u16(st::safety1 + 6);
  s.electrical_flags = r.u24(st::safety2);
  return s;
}

Bytes encode_status(const Status& s, ByteOrder order) {
  Writer w(kStatusSize, order);
  w.f32(st::pressure, s.suction_pressure);
  w.f32(st::pressure + 4, s.discharge_pressure);
  w.f32(st::temperature, s.suction_temperature);
  w.f32(st::temperature + 4, s.discharge_temperature);
  w.f32(st::superheat, s.suction_superheat);
  w.f32(st::superheat + 4, s.discharge_superheat);
  w.u16(st::motor, s.rpm);
  w.u16(st::motor + 2, s.volts);
  w.u16(st::motor + 4, s.watts);
  w.u16(st::motor + 6, s.torque);
  w.u8(st::state, s.op_state);
  w.u8(st::state + 1, s.control_mode);
  w.u8(st::state + 2, s.demand);
  w.u8(st::state + 3, s.remote_enable);
  w.u8(st::state + 4, s.anti_short);
  w.f32(st::motor_temps, s.motor_temperature);
  w.f32(st::motor_temps + 4, s.switch_temperature);
  w.u16(st::safety1, s.compressor_run_flags);
  w.u16(st::safety1 + 2, s.compressor_start_flags);
  w.u16(st::safety1 + 4, s.motor_run_flags);
  w.u16(st::safety1 + 6, s.motor_start_flags);
  w.u24(st::safety2, s.electrical_flags);
  return w.take();
}

std::optional<BuildInfo> parse_build_info(ByteView p, ByteOrder order) {
  if (p.size() < kBuildInfoSize) return std::nullopt;
  const Reader r(p, order);
  BuildInfo b;
  b.model = r.ascii(bi::model, kModelChars);
  b.serial = r.ascii(bi::serial, kSerialChars);
  b.refrigerant = r.u8(bi::compressor);
  b.oil = r.u8(bi::compressor + 1);
  b.min_speed = r.u16(bi::compressor + 4);
  b.max_speed = r.u16(bi::compressor + 6);
  b.voltage = r.u16(bi::electrical);
  b.power = r.u16(bi::electrical + 2);
  b.device_name = r.ascii(bi::name, kDeviceNameChars);
  return b;
}

Bytes encode_build_info(const BuildInfo& b, ByteOrder order) {
  Writer w(kBuildInfoSize, order);
  w.ascii(bi::model, kModelChars, b.model);
  w.ascii(bi::serial, kSerialChars, b.serial);
  w.u8(bi::compressor, b.refrigerant);
  w.u8(bi::compressor + 1, b.oil);
  w.u16(bi::compressor + 4, b.min_speed);
  w.u16(bi::compressor + 6, b.max_speed);
  w.u16(bi::electrical, b.voltage);
  w.u16(bi::electrical + 2, b.power);
  w.ascii(bi::name, kDeviceNameChars, b.device_name);
  return w.take();
}

std::optional<RunningLimits> parse_running_limits(ByteView p, ByteOrder order) {
  if (p.size() < kRunningLimitsSize) return std::nullopt;
  const Reader r(p, order);
  RunningLimits l;
  l.min_speed = r.u16(rl::speed);
  l.max_speed = r.u16(rl::speed + 2);
  l.suction_pressure = r.range(rl::suction_p);
  l.discharge_pressure = r.range(rl::discharge_p);
  l.suction_temperature = r.range(rl::suction_t);
  l.discharge_temperature = r.range(rl::discharge_t);
  l.suction_superheat = r.range(rl::suction_sh);
  l.discharge_superheat = r.range(rl::discharge_sh);
  l.device_id = r.u8(rl::rs485);
  l.control_enabled = r.u8(rl::rs485 + 3);
  return l;
}

Bytes encode_running_limits(const RunningLimits& l, ByteOrder order) {
  Writer w(kRunningLimitsSize, order);
  w.u16(rl::speed, l.min_speed);
  w.u16(rl::speed + 2, l.max_speed);
  w.range(rl::suction_p, l.suction_pressure);
  w.range(rl::discharge_p, l.discharge_pressure);
  w.range(rl::suction_t, l.suction_temperature);
  w.range(rl::discharge_t, l.discharge_temperature);
  w.range(rl::suction_sh, l.suction_superheat);
  w.range(rl::discharge_sh, l.discharge_superheat);
  w.u8(rl::rs485, l.device_id);
  w.u8(rl::rs485 + 3, l.control_enabled);
  return w.take();
}

Bytes encode_speed(std::uint16_t rpm) {
  return {hi8(rpm), lo8(rpm)};
}

std::optional<std::uint16_t> parse_speed(ByteView p) {
  if (p.size() != kSetRunStateSize) return std::nullopt;
  return be16(p[0], p[1]);
}

}  // namespace drivegate::unicla
