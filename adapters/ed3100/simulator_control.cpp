// The simulator's operator commands (`drivegate sim` passes stdin lines to control()).
#include <cstdio>
#include <sstream>

#include "drivegate/sim_text.h"
#include "registers.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::ed3100 {
namespace {

constexpr const char* kUsage =
    "use state | fault <code> | clear | run forward|reverse <0.01 Hz> | silent on|off | "
    "lock on|off | corrupt <n> | "
    "form document|standard | "
    "param <GG-nn> <value> | monitor <0Dnn> <value> <format>|auto | help";

std::optional<std::uint16_t> number(std::string_view s) {
  return parse_uint<std::uint16_t>(s);
}

}  // namespace

std::string Ed3100Simulator::state() const {
  std::ostringstream s;
  s << "address=" << int{address_}
    << " form=" << (form_ == ReadForm::document ? "document" : "standard")
    << " command=" << hex(command_, 4) << " reference=" << hex(reference_, 4)
    << " output=" << output_ << " running=" << running_
    << " direction=" << (rotating_reverse_ ? "reverse" : "forward")
    << " commanded=" << (commanded_reverse_ ? "reverse" : "forward") << " fault=" << hex(fault_, 4)
    << " state=" << hex(state_word(), 4) << " silent=" << silent_ << " lock=" << locked_
    << " corrupt=" << corrupt_;
  for (const auto& [reg, value] : params_) {
    char b[32];
    std::snprintf(b, sizeof b, " param_%02x_%02x=%s", reg >> 8, reg & 0xFF, hex(value, 4).c_str());
    s << b;
  }
  return s.str();
}

std::string Ed3100Simulator::control(std::string_view line, TimePoint /*now*/) {
  std::istringstream in{std::string(line)};
  std::string cmd, a, b, c;
  in >> cmd >> a >> b >> c;
  if (cmd == "state") return state();
  if (cmd == "fault") {
    const auto code = number(a);
    if (!code || *code == kNoFault)
      return "error: fault <code 0..0xFFFE> (the table is not legible)";
    fault_ = *code;
    command_ = kCmdStop;  // a trip coasts the motor
    running_ = false;
    output_ = 0;
    return "ok fault=" + hex(fault_, 4);
  }
  if (cmd == "clear") {
    fault_ = kNoFault;
    return "ok";
  }
  if (cmd == "run" && (a == "forward" || a == "reverse")) {
    // Started at its own keypad (or by the gateway before a restart): running at the reference.
    const auto centi = number(b);
    if (!centi) return "error: run forward|reverse <reference in 0.01 Hz>";
    commanded_reverse_ = rotating_reverse_ = a == "reverse";
    command_ = a == "reverse" ? kCmdReverse : kCmdForward;
    reference_ = output_ = *centi;
    running_ = true;
    return "ok running " + a;
  }
  if (cmd == "silent" && parse_on_off(a)) {
    silent_ = *parse_on_off(a);
    return "ok silent=" + a;
  }
  if (cmd == "lock" && parse_on_off(a)) {
    locked_ = *parse_on_off(a);
    return "ok lock=" + a;
  }
  if (cmd == "corrupt") {
    const auto n = number(a);
    if (!n) return "error: corrupt <count>";
    corrupt_ = *n;
    return "ok corrupt=" + a;
  }
  if (cmd == "form" && (a == "document" || a == "standard")) {
    form_ = a == "document" ? ReadForm::document : ReadForm::standard;
    return "ok form=" + a;
  }
  if (cmd == "param") {
    const auto reg = parse_parameter(a);
    const auto v = number(b);
    if (!reg || !v) return "error: param <GG-nn> <value>";
    params_[*reg] = *v;
    return "ok";
  }
  if (cmd == "monitor") {
    const auto m = parse_monitor(a);
    if (!m) return "error: monitor <0D00..0D28> <value> <format> | monitor <0Dnn> auto";
    if (b == "auto") {
      monitor_override_.erase(m->reg);
      return "ok";
    }
    const auto v = number(b);
    const auto f = number(c);
    if (!v || !f) return "error: monitor <0D00..0D28> <value> <format> | monitor <0Dnn> auto";
    monitor_override_[m->reg] = {*v, *f};
    return "ok";
  }
  if (cmd == "help") return kUsage;
  return std::string("error: unknown command; ") + kUsage;
}

}  // namespace drivegate::ed3100
