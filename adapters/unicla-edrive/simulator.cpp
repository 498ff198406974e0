#include "simulator.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "drivegate/sim_rx.h"
#include "drivegate/sim_text.h"
#include "labels.h"
#include "op_state.h"

namespace drivegate::unicla {

namespace {

// Simulated plant, drivegate's choices (README.md, "Simulator").
constexpr double kRampRpmPerSecond = 1000.0;
constexpr double kCoastRpmPerSecond = 2000.0;
constexpr Millis kStartingTime{500};
constexpr std::size_t kMaxBuffer = 4 * kMaxWireSize;

constexpr const char* kHelp =
    "commands: help | state | fault <motor|overcurrent|overvoltage|undervoltage|overtemp|startup|"
    "pressure|superheat|fmc|electrical|config|xc|<op state number>> | clear | "
    "flags <compressor_run|compressor_start|motor_run|motor_start|electrical> <value> | "
    "sticky on|off | control on|off | limits <min> <max> | run <rpm> | silent on|off | "
    "corrupt <n>";

bool is_fault(OpState s) {
  return is_fault_state(static_cast<std::uint8_t>(s));
}

std::string snake(std::string_view label) {
  std::string out;
  for (const char c : label) {
    if (std::isalnum(static_cast<unsigned char>(c)) != 0) {
      out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
    } else if (!out.empty() && out.back() != '_') {
      out.push_back('_');
    }
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

}  // namespace

EDriveSimulator::EDriveSimulator(std::uint8_t address, ByteOrder order)
    : address_(address), order_(order) {
  build_.model = "EDRIVE-SIM-24V";
  build_.serial = "SIM" + std::to_string(1000000 + address);
  build_.refrigerant = 2;  // R1234YF
  build_.oil = 5;          // POE68
  build_.min_speed = 1000;
  build_.max_speed = 6500;
  build_.voltage = 24;
  build_.power = 2500;
  build_.device_name = "drivegate simulated eDrive " + std::to_string(address);
  limits_.min_speed = 1500;
  limits_.max_speed = 6000;
  limits_.suction_pressure = {1.0F, 6.0F};
  limits_.discharge_pressure = {3.0F, 28.0F};
  limits_.suction_temperature = {-20.0F, 30.0F};
  limits_.discharge_temperature = {0.0F, 120.0F};
  limits_.suction_superheat = {2.0F, 30.0F};
  limits_.discharge_superheat = {5.0F, 60.0F};
  limits_.device_id = address;
  limits_.control_enabled = 1;
}

Status EDriveSimulator::status() const {
  Status s;
  const double f = std::clamp(rpm_ / limits_.max_speed, 0.0, 1.0);
  s.suction_pressure = static_cast<float>(4.5 - 1.5 * f);  // bar-a, equalised at rest
  s.discharge_pressure = static_cast<float>(6.5 + 10.0 * f);
  s.suction_temperature = static_cast<float>(12.0 - 6.0 * f);
  s.discharge_temperature = static_cast<float>(25.0 + 50.0 * f);
  s.suction_superheat = static_cast<float>(5.0 + 3.0 * f);
  s.discharge_superheat = static_cast<float>(10.0 + 25.0 * f);
  s.rpm = static_cast<std::uint16_t>(std::lround(rpm_));
  s.volts = 27;
  s.watts = rpm_ > 0 ? static_cast<std::uint16_t>(std::lround(150.0 + 1800.0 * f)) : 0;
  s.torque =
      rpm_ > 0 ? static_cast<std::uint16_t>(std::lround(s.watts * 60.0 / (6.2832 * rpm_))) : 0;
  s.op_state = raw_ ? raw_state_ : static_cast<std::uint8_t>(state_);
  s.control_mode = 4;  // External Serial
  s.demand = static_cast<std::uint8_t>(target_ * 100 / std::max<int>(1, limits_.max_speed));
  s.remote_enable = 1;
  s.anti_short = 0;
  s.motor_temperature = static_cast<float>(30.0 + 30.0 * f);
  s.switch_temperature = static_cast<float>(35.0 + 25.0 * f);
  s.compressor_run_flags = compressor_run_;
  s.compressor_start_flags = compressor_start_;
  s.motor_run_flags = motor_run_;
  s.motor_start_flags = motor_start_;
  s.electrical_flags = electrical_;
  return s;
}

Bytes EDriveSimulator::on_receive(ByteView rx, TimePoint now) {
  rx_.insert(rx_.end(), rx.begin(), rx.end());
  Bytes out;
  while (const auto d = take_decoded(rx_, [](ByteView b) { return decode(b); })) {
    if (d->status == DecodeStatus::frame) handle(d->frame, now, out);
  }
  if (rx_.size() > kMaxBuffer) rx_.clear();
  return out;
}

void EDriveSimulator::handle(const Frame& f, TimePoint now, Bytes& out) {
  // Only the master's frames for this id or for everyone; replies of other drives pass by.
  if (f.source != kMasterAddress) return;
  if (f.destination != address_ && f.destination != kBroadcastAddress) return;
  if (f.command == static_cast<std::uint8_t>(CommandByte::read)) {
    if (!f.payload.empty()) return;  // "Read: payload 0"
    Bytes payload;
    switch (static_cast<MessageId>(f.message_id)) {
      case MessageId::status:
        payload = encode_status(status(), order_);
        break;
      case MessageId::build_information:
        payload = encode_build_info(build_, order_);
        break;
      case MessageId::running_limits:
        payload = encode_running_limits(limits_, order_);
        break;
      default:
        return;  // no reply to an unknown read
    }
    ++reads_;
    if (silent_) return;
    const Bytes wire = reply(f, std::move(payload));
    out.insert(out.end(), wire.begin(), wire.end());
    return;
  }
  if (f.command != static_cast<std::uint8_t>(CommandByte::write)) return;
  ++writes_;
  if (limits_.control_enabled == 0) return;
  switch (static_cast<MessageId>(f.message_id)) {
    case MessageId::set_run_state:
      if (const auto speed = parse_speed(f.payload)) set_run_state(*speed, now);
      break;
    case MessageId::acknowledge_faults:
      if (f.payload.empty()) acknowledge();
      break;
    default:
      break;
  }
}

void EDriveSimulator::set_run_state(std::uint16_t speed, TimePoint now) {
  if (speed == 0) {  // "Sending a value of 0 is treated as a stop command"
    target_ = 0;
    if (!raw_ && !is_fault(state_)) state_ = OpState::stopped;
    return;
  }
  if (speed < limits_.min_speed || speed > limits_.max_speed) return;  // ignored
  if (raw_ || is_fault(state_)) return;
  target_ = speed;
  if (state_ != OpState::running && state_ != OpState::starting) {
    state_ = OpState::starting;
    starting_since_ = now;
  }
}

void EDriveSimulator::acknowledge() {
  if (sticky_) return;  // the condition persists: the fault stays
  if (raw_ || is_fault(state_)) {
    raw_ = false;
    state_ = OpState::stopped;
  }
  compressor_run_ = compressor_start_ = motor_run_ = motor_start_ = 0;
  electrical_ = 0;
}

void EDriveSimulator::trip(OpState state) {
  state_ = state;
  raw_ = false;
  target_ = 0;
}

Bytes EDriveSimulator::reply(const Frame& request, Bytes payload) {
  Frame r;
  r.source = address_;  // "all devices will reply with their individual device ids"
  r.destination = kMasterAddress;
  r.command = request.command;
  r.message_id = request.message_id;
  r.sequence = request.sequence;  // "The slave reply will contain this sequence number"
  r.payload = std::move(payload);
  Bytes body = frame_body(r);
  if (corrupt_ > 0) {
    --corrupt_;
    body.back() ^= 0xFF;
  }
  return wrap(body);
}

Bytes EDriveSimulator::on_tick(TimePoint now) {
  if (!ticked_) {
    ticked_ = true;
    last_tick_ = now;
    return {};
  }
  const double dt = std::chrono::duration<double>(now - last_tick_).count();
  last_tick_ = now;
  if (state_ == OpState::starting && now - starting_since_ >= kStartingTime) {
    state_ = OpState::running;
  }
  const bool driving = !raw_ && (state_ == OpState::starting || state_ == OpState::running);
  const double goal = driving ? target_ : 0.0;
  const double step = (driving ? kRampRpmPerSecond : kCoastRpmPerSecond) * dt;
  if (rpm_ < goal) rpm_ = std::min(goal, rpm_ + step);
  if (rpm_ > goal) rpm_ = std::max(goal, rpm_ - step);
  return {};
}

std::string EDriveSimulator::fault_command(std::string_view arg) {
  // The flag word a named fault sets a bit in, beside its Fault-* state.
  enum class Word : std::uint8_t { none, compressor_run, motor_run, electrical };
  struct Named {
    std::string_view name;
    OpState state;
    Word word;
    unsigned bit;
  };
  // Bits of "Interpreting Safety Flags": motor 14 ST Motor Control - Over Current, 9 Over voltage,
  // 10 Under Voltage, 11 Over Temperature, 12 Startup Fail; compressor 14 High Side Pressure High,
  // 5 Low Side Superheat Low; electrical 1 FMC 3.3V Fault, 16 CMC 3V3 Fault.
  static constexpr Named kNamed[] = {
      {"motor", OpState::fault_motor, Word::motor_run, 14},
      {"overcurrent", OpState::fault_motor, Word::motor_run, 14},
      {"overvoltage", OpState::fault_motor, Word::motor_run, 9},
      {"undervoltage", OpState::fault_motor, Word::motor_run, 10},
      {"overtemp", OpState::fault_motor, Word::motor_run, 11},
      {"startup", OpState::fault_motor, Word::motor_run, 12},
      {"pressure", OpState::fault_compressor_safety, Word::compressor_run, 14},
      {"superheat", OpState::fault_compressor_safety, Word::compressor_run, 5},
      {"fmc", OpState::fault_fmc, Word::electrical, 1},
      {"electrical", OpState::fault_electrical, Word::electrical, 16},
      {"config", OpState::fault_configuration, Word::none, 0},
      {"xc", OpState::fault_xc_comms, Word::none, 0},
  };
  for (const Named& n : kNamed) {
    if (n.name != arg) continue;
    trip(n.state);
    switch (n.word) {
      case Word::compressor_run:
        compressor_run_ |= static_cast<std::uint16_t>(1u << n.bit);
        break;
      case Word::motor_run:
        motor_run_ |= static_cast<std::uint16_t>(1u << n.bit);
        break;
      case Word::electrical:
        electrical_ |= 1u << n.bit;
        break;
      case Word::none:
        break;
    }
    return "ok " + state_line();
  }
  if (const auto raw = parse_unsigned(arg, 0xFF)) {
    trip(OpState::stopped);
    raw_ = true;
    raw_state_ = static_cast<std::uint8_t>(*raw);
    return "ok " + state_line();
  }
  return std::string("error: unknown fault '") + std::string(arg) + "'; " + kHelp;
}

std::string EDriveSimulator::flags_command(std::string_view word, std::string_view value) {
  const auto v = parse_unsigned(value);
  if (!v) return std::string("error: bad flag value; ") + kHelp;
  const auto w16 = static_cast<std::uint16_t>(*v & 0xFFFF);
  if (word == "compressor_run") {
    compressor_run_ = w16;
  } else if (word == "compressor_start") {
    compressor_start_ = w16;
  } else if (word == "motor_run") {
    motor_run_ = w16;
  } else if (word == "motor_start") {
    motor_start_ = w16;
  } else if (word == "electrical") {
    electrical_ = *v & 0xFFFFFF;  // "Electrical Safety Flags": 24 bits
  } else {
    return std::string("error: unknown flag word; ") + kHelp;
  }
  return "ok " + state_line();
}

std::string EDriveSimulator::control(std::string_view line, TimePoint /*now*/) {
  const auto w = split_words(line);
  if (w.empty()) return std::string("error: empty command; ") + kHelp;
  const std::string_view cmd = w[0];
  if (cmd == "help" && w.size() == 1) return kHelp;
  if (cmd == "state" && w.size() == 1) return state_line();
  if (cmd == "fault" && w.size() == 2) return fault_command(w[1]);
  if (cmd == "clear" && w.size() == 1) {
    const bool keep = sticky_;
    sticky_ = false;
    acknowledge();
    sticky_ = keep;
    return "ok " + state_line();
  }
  if (cmd == "flags" && w.size() == 3) return flags_command(w[1], w[2]);
  if ((cmd == "sticky" || cmd == "control" || cmd == "silent") && w.size() == 2) {
    const auto b = parse_on_off(w[1]);
    if (!b) return std::string("error: expected on or off; ") + kHelp;
    if (cmd == "sticky") sticky_ = *b;
    if (cmd == "control") limits_.control_enabled = *b ? 1 : 0;
    if (cmd == "silent") silent_ = *b;
    return "ok " + state_line();
  }
  if (cmd == "run" && w.size() == 2) {
    // Started by another master (or before the gateway restarted): running at `rpm` already.
    const auto rpm = parse_unsigned(w[1], 0xFFFF);
    if (!rpm || *rpm == 0) return std::string("error: expected a speed; ") + kHelp;
    target_ = static_cast<std::uint16_t>(*rpm);
    rpm_ = static_cast<double>(*rpm);
    state_ = OpState::running;
    return "ok " + state_line();
  }
  if (cmd == "corrupt" && w.size() == 2) {
    const auto n = parse_unsigned(w[1], 0xFFFF);
    if (!n) return std::string("error: expected a count; ") + kHelp;
    corrupt_ = static_cast<int>(*n);
    return "ok " + state_line();
  }
  if (cmd == "limits" && w.size() == 3) {
    const auto lo = parse_unsigned(w[1], 0xFFFF);  // "Speed Control": u16 rpm
    const auto hi = parse_unsigned(w[2], 0xFFFF);
    if (!lo || !hi || *lo > *hi) {
      return std::string("error: expected 0 <= min <= max <= 65535; ") + kHelp;
    }
    limits_.min_speed = static_cast<std::uint16_t>(*lo);
    limits_.max_speed = static_cast<std::uint16_t>(*hi);
    return "ok " + state_line();
  }
  return "error: unknown command '" + std::string(line) + "'; " + kHelp;
}

std::string EDriveSimulator::state_line() const {
  const Status s = status();
  std::ostringstream o;
  o << "address=" << int{address_} << " op_state=" << int{s.op_state} << " op_state_name="
    << (s.op_state < kOpStateNames.size() ? snake(kOpStateNames[s.op_state]) : "unknown")
    << " rpm=" << s.rpm << " target=" << target_ << " min=" << limits_.min_speed
    << " max=" << limits_.max_speed << " suction_pressure=" << s.suction_pressure
    << " discharge_pressure=" << s.discharge_pressure
    << " compressor_run=" << hex(compressor_run_, 4)
    << " compressor_start=" << hex(compressor_start_, 4) << " motor_run=" << hex(motor_run_, 4)
    << " motor_start=" << hex(motor_start_, 4) << " electrical=" << hex(electrical_, 6)
    << " control=" << (limits_.control_enabled != 0 ? "on" : "off")
    << " sticky=" << (sticky_ ? "on" : "off") << " silent=" << (silent_ ? "on" : "off")
    << " corrupt=" << corrupt_ << " reads=" << reads_ << " writes=" << writes_;
  return o.str();
}

}  // namespace drivegate::unicla
