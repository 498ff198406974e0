// NidecWasherSimulator: operator commands (`drivegate sim nidec-washer` passes stdin lines here).
#include <cstdio>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "drivegate/sim_text.h"
#include "faults.h"
#include "simulator.h"

namespace drivegate::nidec {
namespace {

constexpr const char* kHelp =
    "state, fault <name|raw>, clear, silent on|off, corrupt N, nack N, load N (x100 g), "
    "bus V, fabric N, version N, help";

// Decimal or 0x-prefixed hexadecimal, within [0, max].
std::optional<long> number(const std::string& s, long max) {
  if (const auto v = parse_unsigned(s, static_cast<std::uint32_t>(max))) return long{*v};
  return std::nullopt;
}

constexpr const char* kMotionNames[] = {
    "stopped", "cw", "ccw", "agitation", "spin", "free_shaft_spin", "stopping", "braking"};

}  // namespace

std::string NidecWasherSimulator::state() const {
  std::ostringstream s;
  s << "pinged=" << pinged_ << " platform=" << int{platform_} << " empty_raw_weight=" << empty_raw_
    << " version=" << hex(version_, 4) << " motion=" << kMotionNames[static_cast<int>(motion_)]
    << " target_rpm=" << target_ << " speed_rpm=" << speed() << " faults=" << hex(faults_, 2)
    << " forced_brake=" << forced_brake_ << " dc_bus=" << dc_bus_ << " load=" << int{load_}
    << " weighing=" << weighing_since_.has_value() << " weight=" << int{weight()}
    << " raw_weight=" << raw_weight() << " fabric=" << int{fabric_} << " silent=" << silent_
    << " corrupt=" << corrupt_ << " nack=" << nack_ << " comm_fault=" << comm_fault_
    << " frames=" << frames_ << " nacks_sent=" << nacks_sent_;
  return s.str();
}

std::string NidecWasherSimulator::control(std::string_view text, TimePoint now) {
  advance(now);
  const ControlLine line(text, kHelp);
  if (auto answer = line.common()) return *answer;
  const std::vector<std::string>& w = line.words();
  const std::string& cmd = w[0];
  const std::optional<long> arg = w.size() == 2 ? number(w[1], 65535) : std::nullopt;
  if (cmd == "state" && w.size() == 1) return state();
  if (cmd == "clear" && w.size() == 1) {
    faults_ = 0;
    clear_at_ = {};
    return "ok faults=0x00";
  }
  if (cmd == "fault" && w.size() == 2) {
    std::optional<std::uint8_t> bits = fault_mask(w[1]);
    if (!bits) {
      if (const auto raw = number(w[1], 0xFF); raw && *raw != 0) {
        bits = static_cast<std::uint8_t>(*raw);
      }
    }
    if (!bits) return line.error("fault takes " + fault_names() + " or a raw bitmask 1..0xFF");
    trip(*bits, now);
    return "ok faults=" + hex(faults_, 2);
  }
  if (cmd == "silent" && w.size() == 2 && parse_on_off(w[1])) {
    silent_ = *parse_on_off(w[1]);
    rx_.clear();
    return std::string("ok silent=") + (silent_ ? "1" : "0");
  }
  const long n = arg.value_or(-1);
  if (n < 0) return line.unknown();
  // `field` set to the argument, and the line that says so.
  const auto set = [n](auto& field, const char* name) {
    field = static_cast<std::remove_reference_t<decltype(field)>>(n);
    return std::string("ok ") + name + "=" + std::to_string(field);
  };
  if (cmd == "corrupt") return set(corrupt_, "corrupt");
  if (cmd == "nack") return set(nack_, "nack");
  if (cmd == "load" && n <= 0xFF) return set(load_, "load");
  if (cmd == "bus") return set(dc_bus_, "dc_bus");
  if (cmd == "fabric" && n <= 0xFF) return set(fabric_, "fabric");
  if (cmd == "version") {
    version_ = static_cast<std::uint16_t>(n);
    return "ok version=" + hex(version_, 4);
  }
  return line.unknown();
}

}  // namespace drivegate::nidec
