#include "config.h"

#include <algorithm>
#include <cctype>

#include "registers.h"

namespace drivegate::ed3100 {
namespace {

std::optional<unsigned> hex_digits(std::string_view s) {
  if (s.empty()) return std::nullopt;
  unsigned v = 0;
  for (const char c : s) {
    const int u = std::toupper(static_cast<unsigned char>(c));
    unsigned d = 0;
    if (u >= '0' && u <= '9') {
      d = static_cast<unsigned>(u - '0');
    } else if (u >= 'A' && u <= 'F') {
      d = static_cast<unsigned>(u - 'A' + 10);
    } else {
      return std::nullopt;
    }
    v = v * 16 + d;
  }
  return v;
}

}  // namespace

std::optional<MonitorSel> parse_monitor(std::string_view text) {
  MonitorSel m;
  if (const auto colon = text.find(':'); colon != std::string_view::npos) {
    m.unit = std::string(text.substr(colon + 1));
    text = text.substr(0, colon);
    if (m.unit != "V" && m.unit != "Hz" && m.unit != "A") return std::nullopt;
  }
  if (text.size() != 4) return std::nullopt;
  const auto v = hex_digits(text);
  if (!v || *v < kRegMonitorFirst || *v > kRegMonitorLast) return std::nullopt;
  m.reg = static_cast<std::uint16_t>(*v);
  return m;
}

std::optional<std::uint16_t> parse_parameter(std::string_view text) {
  if (text.size() != 5 || text[2] != '-') return std::nullopt;
  const auto gg = hex_digits(text.substr(0, 2));
  const auto nn = hex_digits(text.substr(3, 2));
  if (!gg || !nn || *gg > kParamGroupMax) return std::nullopt;
  return static_cast<std::uint16_t>((*gg << 8) | *nn);
}

std::optional<Config> make_config(std::uint32_t address, const Options& options,
                                  std::string& error) {
  Config c;
  if (address > 31) {  // document, "Address": 0 ~ 31
    error = "address: the ED3100 takes 0 (broadcast) or 1..31";
    return std::nullopt;
  }
  c.address = static_cast<std::uint8_t>(address);
  c.poles = static_cast<int>(options.integer("poles"));
  if (c.poles < 2 || c.poles % 2 != 0) {
    error = "poles: must be an even number of at least 2";
    return std::nullopt;
  }
  for (const auto& s : options.string_list("monitors")) {
    auto m = parse_monitor(s);
    if (!m) {
      error = "monitors: \"" + s + "\" is not a monitor 0D00..0D28 (optionally :V, :Hz or :A)";
      return std::nullopt;
    }
    const bool dup = std::any_of(c.monitors.begin(), c.monitors.end(),
                                 [&](const MonitorSel& x) { return x.reg == m->reg; });
    if (dup) {
      error = "monitors: \"" + s + "\" is listed twice";
      return std::nullopt;
    }
    c.monitors.push_back(*m);
  }
  const auto speed = parse_monitor(options.string("speed_monitor"));
  if (!speed) {
    error = "speed_monitor: not a monitor 0D00..0D28";
    return std::nullopt;
  }
  const auto it = std::find_if(c.monitors.begin(), c.monitors.end(),
                               [&](const MonitorSel& x) { return x.reg == speed->reg; });
  if (it == c.monitors.end()) {
    c.monitors.push_back({speed->reg, "Hz"});
    c.speed_monitor = c.monitors.size() - 1;
  } else {
    if (it->unit.empty()) it->unit = "Hz";
    c.speed_monitor = static_cast<std::size_t>(it - c.monitors.begin());
  }
  for (const auto& s : options.string_list("parameters")) {
    const auto p = parse_parameter(s);
    if (!p) {
      error = "parameters: \"" + s + "\" is not a parameter GG-nn with GG 00..0C";
      return std::nullopt;
    }
    if (std::find(c.parameters.begin(), c.parameters.end(), *p) != c.parameters.end()) {
      error = "parameters: \"" + s + "\" is listed twice";
      return std::nullopt;
    }
    c.parameters.push_back(*p);
  }
  c.frame_gap = Millis(options.integer("frame_gap_ms"));
  c.timeout = Millis(options.integer("timeout_ms"));
  c.attempts = static_cast<std::uint8_t>(options.integer("attempts"));
  c.comm_timeout = Millis(options.integer("comm_timeout_ms"));
  c.reset_register = static_cast<std::uint16_t>(options.integer("reset_register"));
  c.reset_value = static_cast<std::uint16_t>(options.integer("reset_value"));
  return c;
}

}  // namespace drivegate::ed3100
