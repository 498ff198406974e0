#include "settings.h"

#include <algorithm>
#include <cctype>

#include "registers.h"

namespace drivegate::ed3100 {
namespace {

// Document, "Address": 0 ~ 31, 0 being the broadcast.
constexpr std::uint32_t kAddressMax = 31;

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

// Monitors as listed, each once; the speed monitor added (in Hz) when it is not among them.
bool parse_monitors(const Options& options, Settings& s, std::string& error) {
  for (const auto& text : options.string_list("monitors")) {
    auto m = parse_monitor(text);
    if (!m) {
      error = "monitors: \"" + text + "\" is not a monitor 0D00..0D28 (optionally :V, :Hz or :A)";
      return false;
    }
    const bool listed = std::any_of(s.monitors.begin(), s.monitors.end(),
                                    [&](const MonitorSel& x) { return x.reg == m->reg; });
    if (listed) {
      error = "monitors: \"" + text + "\" is listed twice";
      return false;
    }
    s.monitors.push_back(*m);
  }
  const auto speed = parse_monitor(options.string("speed_monitor"));
  if (!speed) {
    error = "speed_monitor: not a monitor 0D00..0D28";
    return false;
  }
  const auto it = std::find_if(s.monitors.begin(), s.monitors.end(),
                               [&](const MonitorSel& x) { return x.reg == speed->reg; });
  if (it == s.monitors.end()) {
    s.monitors.push_back({speed->reg, "Hz"});
    s.speed_monitor = s.monitors.size() - 1;
  } else {
    if (it->unit.empty()) it->unit = "Hz";
    s.speed_monitor = static_cast<std::size_t>(it - s.monitors.begin());
  }
  return true;
}

bool parse_parameters(const Options& options, Settings& s, std::string& error) {
  for (const auto& text : options.string_list("parameters")) {
    const auto p = parse_parameter(text);
    if (!p) {
      error = "parameters: \"" + text + "\" is not a parameter GG-nn with GG 00..0C";
      return false;
    }
    if (std::find(s.parameters.begin(), s.parameters.end(), *p) != s.parameters.end()) {
      error = "parameters: \"" + text + "\" is listed twice";
      return false;
    }
    s.parameters.push_back(*p);
  }
  return true;
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

std::optional<Settings> parse_settings(const Options& options, std::string& error) {
  Settings s;
  s.poles = static_cast<int>(options.integer("poles"));
  // rpm = Hz x 120 / poles: a motor has pole pairs.
  if (s.poles < 2 || s.poles % 2 != 0) {
    error = "poles: must be an even number of at least 2";
    return std::nullopt;
  }
  if (!parse_monitors(options, s, error) || !parse_parameters(options, s, error)) {
    return std::nullopt;
  }
  s.frame_gap = Millis(options.integer("frame_gap_ms"));
  s.timeout = Millis(options.integer("timeout_ms"));
  s.attempts = static_cast<std::uint8_t>(options.integer("attempts"));
  s.comm_timeout = Millis(options.integer("comm_timeout_ms"));
  s.reset_register = static_cast<std::uint16_t>(options.integer("reset_register"));
  s.reset_value = static_cast<std::uint16_t>(options.integer("reset_value"));
  s.sim_reply_form =
      options.string("sim_reply_form") == "standard" ? ReadForm::standard : ReadForm::document;
  return s;
}

std::optional<std::uint8_t> device_address(std::uint32_t address, std::string& error) {
  if (address > kAddressMax) {
    error = "address: the ED3100 takes 0 (broadcast) or 1..31";
    return std::nullopt;
  }
  return static_cast<std::uint8_t>(address);
}

}  // namespace drivegate::ed3100
