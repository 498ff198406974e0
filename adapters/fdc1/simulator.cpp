#include "simulator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "drivegate/sim_rx.h"
#include "drivegate/sim_text.h"
#include "faults.h"
#include "program.h"

namespace drivegate::fdc1 {
namespace {

// Line noise the simulator can inject: contains the first header byte (1B) followed by bytes
// that cannot continue a header, so a receiver must resynchronise.
constexpr std::array<std::uint8_t, 8> kNoise = {0x00, 0x1B, 0xFF, 0x4D, 0x55, 0x1B, 0x1B, 0xAA};

constexpr std::string_view kCommands =
    "state, fault <battery|fan|start|overload|temperature|fan_eor|start_eor|overload_eor|"
    "temperature_eor|internal|raw>, clear, silent on|off, deaf on|off, corrupt N, noise N, "
    "mangle N, delay S, thermostat on|off, window S, run RPM (slave mode), help";

}  // namespace

// Slave mode starts stopped (the stop frame the driver sends); normal mode with the specs
// README's example range, 2000..3000 rpm, as if programmed so.
Fdc1Simulator::Fdc1Simulator(const Settings& settings)
    : mode_(settings.slave_mode ? kModeSlave : 0),
      speed_(settings.slave_mode ? Speed{0, kMaxRpm} : Speed{2000, 3000}) {}

Bytes Fdc1Simulator::on_receive(ByteView rx, TimePoint now) {
  if (deaf_) return {};  // the master's bytes never reach the UART
  if (rx_.empty()) rx_since_ = now;
  rx_.insert(rx_.end(), rx.begin(), rx.end());
  Bytes out;
  while (const auto d = take_decoded(rx_, [](ByteView b) { return decode_master(b); })) {
    rx_since_ = now;
    if (d->status == DecodeStatus::bad) {
      ++rejected_;  // INPUT: bad checksums are ignored by the device
      continue;
    }
    if (const auto* s = std::get_if<Speed>(&d->frame)) {
      handle(*s, now);
    } else {
      const Bytes echo = handle(std::get<Program>(d->frame));
      out.insert(out.end(), echo.begin(), echo.end());
    }
  }
  if (silent_) return {};
  return out;
}

void Fdc1Simulator::handle(const Speed& s, TimePoint now) {
  const bool slave = is_slave(mode_);
  const auto in_range = [](std::uint16_t v) { return v >= kMinRpm && v <= kMaxRpm; };
  // INPUT, Programming speed: 1500..3500 rpm; in slave mode min 0 stops, max is irrelevant.
  const bool ok = slave ? (s.min_rpm == 0 || in_range(s.min_rpm))
                        : (in_range(s.min_rpm) && in_range(s.max_rpm) && s.min_rpm <= s.max_rpm);
  if (!ok) {
    ++rejected_;
    return;
  }
  ++speeds_;
  speed_ = s;
  last_speed_ = now;
  watchdog_tripped_ = false;
}

Bytes Fdc1Simulator::handle(const Program& p) {
  ++programs_;
  stored_ = p;
  mode_ = p.mode;
  if (!is_slave(mode_)) speed_ = {p.min_rpm, p.max_rpm};
  Program echoed = p;
  if (mangle_ > 0) {
    --mangle_;
    echoed.min_rpm = static_cast<std::uint16_t>(echoed.min_rpm + 1);
  }
  return emit(encode_echo(echoed));
}

double Fdc1Simulator::target_rpm() const {
  if (alarm_ != 0 || restart_left_s_ > 0) return 0;
  if (is_slave(mode_)) return watchdog_tripped_ ? 0 : speed_.min_rpm;
  return thermostat_ ? speed_.max_rpm : 0;
}

void Fdc1Simulator::step(TimePoint now) {
  const double dt = std::chrono::duration<double>(now - last_tick_).count();
  last_tick_ = now;
  if (!rx_.empty() && now - rx_since_ > kFrameWindow) rx_.clear();
  if (is_slave(mode_) && !watchdog_tripped_ && now - last_speed_ > watchdog_) {
    watchdog_tripped_ = true;
  }
  restart_left_s_ = std::max(0.0, restart_left_s_ - dt);
  const double target = target_rpm();
  if (target <= 0) {
    motor_on_ = false;
    rpm_ = 0;
    return;
  }
  if (!motor_on_) {
    motor_on_ = true;
    rpm_ = std::min<double>(target, kMinRpm);
  }
  const double step_rpm = kRampRpmPerS * dt;
  rpm_ = rpm_ < target ? std::min(target, rpm_ + step_rpm) : std::max(target, rpm_ - step_rpm);
}

Status Fdc1Simulator::status() const {
  Status s;
  s.motor_on = motor_on_;
  if (motor_on_) {
    s.rpm = static_cast<std::uint16_t>(std::lround(rpm_));
    s.word = static_cast<std::uint16_t>(std::lround(rpm_ * kAmpsPerRpm * kCurrentScale));
  } else {
    s.alarm = alarm_;
    s.word = static_cast<std::uint16_t>(std::min(65535L, std::lround(restart_left_s_ * kRestartScale)));
  }
  return s;
}

Bytes Fdc1Simulator::emit(Bytes frame) {
  if (corrupt_ > 0) {
    --corrupt_;
    frame.back() ^= 0xFF;  // checksum_even
  }
  return frame;
}

Bytes Fdc1Simulator::on_tick(TimePoint now) {
  if (!started_) {
    started_ = true;
    last_tick_ = now;
    next_stream_ = now;
    last_speed_ = now;
  }
  step(now);
  if (now < next_stream_) return {};
  next_stream_ += kStreamPeriod;
  if (next_stream_ <= now) next_stream_ = now + kStreamPeriod;
  if (silent_) return {};
  Bytes out;
  for (; noise_ > 0; --noise_) out.push_back(kNoise[noise_ % kNoise.size()]);
  ++frames_;
  const Bytes frame = emit(encode_status(status()));
  out.insert(out.end(), frame.begin(), frame.end());
  return out;
}

std::string Fdc1Simulator::state(TimePoint now) const {
  std::ostringstream o;
  char amps[16];
  std::snprintf(amps, sizeof amps, "%.2f", motor_on_ ? rpm_ * kAmpsPerRpm : 0.0);
  const auto age = std::chrono::duration_cast<Millis>(now - last_speed_).count();
  o << "motor=" << (motor_on_ ? "on" : "off") << " rpm=" << std::lround(rpm_)
    << " target=" << static_cast<int>(target_rpm()) << " current_a=" << amps
    << " alarm=" << int{alarm_} << " restart_s=" << std::lround(restart_left_s_)
    << " mode=" << int{mode_} << " slave=" << (is_slave(mode_) ? 1 : 0) << " min=" << speed_.min_rpm
    << " max=" << speed_.max_rpm << " speed_age_ms=" << age
    << " watchdog=" << (watchdog_tripped_ ? 1 : 0)
    << " window_s=" << std::chrono::duration_cast<std::chrono::seconds>(watchdog_).count()
    << " thermostat=" << (thermostat_ ? 1 : 0) << " silent=" << (silent_ ? 1 : 0)
    << " deaf=" << (deaf_ ? 1 : 0) << " corrupt=" << corrupt_ << " noise=" << noise_
    << " mangle=" << mangle_ << " speeds=" << speeds_ << " programs=" << programs_
    << " rejected=" << rejected_ << " frames=" << frames_;
  return o.str();
}

std::string Fdc1Simulator::control(std::string_view line, TimePoint now) {
  const std::vector<std::string> words = split_words(line);
  const std::string cmd = words.empty() ? std::string() : words[0];
  const std::string arg = words.size() > 1 ? words[1] : std::string();
  const auto number = parse_unsigned(arg);
  const auto on_off = [&](bool& flag) -> std::string {
    const auto on = parse_on_off(arg);
    if (!on) return "error: " + cmd + " takes on|off";
    flag = *on;
    return "ok";
  };
  if (cmd == "state") return state(now);
  if (cmd == "help") return "commands: " + std::string(kCommands);
  if (cmd == "fault") {
    if (const auto a = find_alarm(arg)) {
      alarm_ = a->first;
      return "ok";
    }
    if (number && *number > 0 && *number <= 255) {  // OUTPUT: A is one byte
      alarm_ = static_cast<std::uint8_t>(*number);
      return "ok";
    }
    return "error: fault takes a name or a raw code 1..255; commands: " + std::string(kCommands);
  }
  if (cmd == "clear") {
    alarm_ = 0;
    return "ok";
  }
  if (cmd == "silent") return on_off(silent_);
  if (cmd == "deaf") return on_off(deaf_);
  if (cmd == "thermostat") return on_off(thermostat_);
  if (cmd == "corrupt" || cmd == "noise" || cmd == "mangle" || cmd == "delay") {
    if (!number || *number > 100000) return "error: " + cmd + " takes a count";
    if (cmd == "corrupt") corrupt_ = static_cast<int>(*number);
    if (cmd == "noise") noise_ = *number;
    if (cmd == "mangle") mangle_ = static_cast<int>(*number);
    if (cmd == "delay") restart_left_s_ = static_cast<double>(*number);
    return "ok";
  }
  if (cmd == "run") {
    // Slave mode: running at <rpm> on the speed frames of an earlier session (a gateway that
    // restarted), as if they had just arrived.
    if (!is_slave(mode_)) return "error: run is for slave mode";
    if (!number || *number < kMinRpm || *number > kMaxRpm) return "error: run takes 1500..3500";
    const auto rpm = static_cast<std::uint16_t>(*number);
    speed_ = {rpm, rpm};
    last_speed_ = now;
    watchdog_tripped_ = false;
    motor_on_ = true;
    rpm_ = rpm;
    return "ok";
  }
  if (cmd == "window") {
    // Shortens the slave-mode watchdog so a test can outlast it in seconds; never longer than
    // the document's 60 s.
    const auto shortest = std::chrono::duration_cast<std::chrono::seconds>(kMinWatchdog).count();
    if (!number || *number < shortest || *number > kSlaveWatchdog.count()) {
      return "error: window takes 1..60 (seconds)";
    }
    watchdog_ = std::chrono::seconds(*number);
    return "ok";
  }
  return "error: unknown command '" + cmd + "'; commands: " + std::string(kCommands);
}

}  // namespace drivegate::fdc1
