#include "payloads.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <utility>

namespace drivegate::unicla {

namespace {

// Reads fields at fixed offsets of a payload into their variables: a layout (below) read.
class Reader {
 public:
  Reader(ByteView p, ByteOrder order) : p_(p), order_(order) {}
  void u8(std::size_t at, std::uint8_t& v) const { v = p_[at]; }
  void u16(std::size_t at, std::uint16_t& v) const { v = be16(p_[at], p_[at + 1]); }
  void u24(std::size_t at, std::uint32_t& v) const {
    v = (std::uint32_t{p_[at]} << 16) | (std::uint32_t{p_[at + 1]} << 8) | p_[at + 2];
  }
  void f32(std::size_t at, float& v) const {
    std::uint32_t raw = 0;
    for (std::size_t i = 0; i < 4; ++i) {
      const std::size_t k = order_ == ByteOrder::big ? i : 3 - i;
      raw = (raw << 8) | p_[at + k];
    }
    v = std::bit_cast<float>(raw);
  }
  void range(std::size_t at, Range& r) const {
    f32(at, r.low);
    f32(at + 4, r.high);
  }
  void ascii(std::size_t at, std::size_t n, std::string& s) const {
    s.assign(reinterpret_cast<const char*>(p_.data() + at), n);
    // Fields are padded: drivegate cuts at the first NUL and drops trailing spaces.
    if (const auto nul = s.find('\0'); nul != std::string::npos) s.resize(nul);
    while (!s.empty() && s.back() == ' ') s.pop_back();
  }

 private:
  ByteView p_;
  ByteOrder order_;
};

// Writes variables at their fields' fixed offsets of a zero-filled payload: a layout (below)
// written.
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

// Each payload's layout, once: `fields(io, x)` has `io` (a Reader or a Writer) take every field
// at its offset, `x` (the payload's struct, const when written) holding its value.
template <class T>
struct Layout;

template <>
struct Layout<Status> {
  static constexpr std::size_t size = kStatusSize;
  template <class Io, class S>
  static void fields(Io& io, S& s) {
    io.f32(st::pressure, s.suction_pressure);
    io.f32(st::pressure + 4, s.discharge_pressure);
    io.f32(st::temperature, s.suction_temperature);
    io.f32(st::temperature + 4, s.discharge_temperature);
    io.f32(st::superheat, s.suction_superheat);
    io.f32(st::superheat + 4, s.discharge_superheat);
    io.u16(st::motor, s.rpm);
    io.u16(st::motor + 2, s.volts);
    io.u16(st::motor + 4, s.watts);
    io.u16(st::motor + 6, s.torque);
    io.u8(st::state, s.op_state);
    io.u8(st::state + 1, s.control_mode);
    io.u8(st::state + 2, s.demand);
    io.u8(st::state + 3, s.remote_enable);
    io.u8(st::state + 4, s.anti_short);
    io.f32(st::motor_temps, s.motor_temperature);
    io.f32(st::motor_temps + 4, s.switch_temperature);
    io.u16(st::safety1, s.compressor_run_flags);
    io.u16(st::safety1 + 2, s.compressor_start_flags);
    io.u16(st::safety1 + 4, s.motor_run_flags);
    io.u16(st::safety1 + 6, s.motor_start_flags);
    io.u24(st::safety2, s.electrical_flags);
  }
};

template <>
struct Layout<BuildInfo> {
  static constexpr std::size_t size = kBuildInfoSize;
  template <class Io, class B>
  static void fields(Io& io, B& b) {
    io.ascii(bi::model, kModelChars, b.model);
    io.ascii(bi::serial, kSerialChars, b.serial);
    io.u8(bi::compressor, b.refrigerant);
    io.u8(bi::compressor + 1, b.oil);
    io.u16(bi::compressor + 4, b.min_speed);
    io.u16(bi::compressor + 6, b.max_speed);
    io.u16(bi::electrical, b.voltage);
    io.u16(bi::electrical + 2, b.power);
    io.ascii(bi::name, kDeviceNameChars, b.device_name);
  }
};

template <>
struct Layout<RunningLimits> {
  static constexpr std::size_t size = kRunningLimitsSize;
  template <class Io, class L>
  static void fields(Io& io, L& l) {
    io.u16(rl::speed, l.min_speed);
    io.u16(rl::speed + 2, l.max_speed);
    io.range(rl::suction_p, l.suction_pressure);
    io.range(rl::discharge_p, l.discharge_pressure);
    io.range(rl::suction_t, l.suction_temperature);
    io.range(rl::discharge_t, l.discharge_temperature);
    io.range(rl::suction_sh, l.suction_superheat);
    io.range(rl::discharge_sh, l.discharge_superheat);
    io.u8(rl::rs485, l.device_id);
    io.u8(rl::rs485 + 3, l.control_enabled);
  }
};

// A payload of at least its layout's size, read; nothing when it is shorter.
template <class T>
std::optional<T> parse(ByteView p, ByteOrder order) {
  if (p.size() < Layout<T>::size) return std::nullopt;
  const Reader r(p, order);
  T x;
  Layout<T>::fields(r, x);
  return x;
}

template <class T>
Bytes encode(const T& x, ByteOrder order) {
  Writer w(Layout<T>::size, order);
  Layout<T>::fields(w, x);
  return w.take();
}

}  // namespace

std::optional<Status> parse_status(ByteView p, ByteOrder order) {
  return parse<Status>(p, order);
}
Bytes encode_status(const Status& s, ByteOrder order) {
  return encode(s, order);
}
std::optional<BuildInfo> parse_build_info(ByteView p, ByteOrder order) {
  return parse<BuildInfo>(p, order);
}
Bytes encode_build_info(const BuildInfo& b, ByteOrder order) {
  return encode(b, order);
}
std::optional<RunningLimits> parse_running_limits(ByteView p, ByteOrder order) {
  return parse<RunningLimits>(p, order);
}
Bytes encode_running_limits(const RunningLimits& l, ByteOrder order) {
  return encode(l, order);
}

Bytes encode_speed(std::uint16_t rpm) {
  return {hi8(rpm), lo8(rpm)};
}

std::optional<std::uint16_t> parse_speed(ByteView p) {
  if (p.size() != kSetRunStateSize) return std::nullopt;
  return be16(p[0], p[1]);
}

}  // namespace drivegate::unicla
