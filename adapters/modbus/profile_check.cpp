#include "profile_check.h"

#include <algorithm>
#include <variant>

#include "profile.h"
#include "profile_examples.h"

namespace drivegate::modbus_device {
namespace {

std::vector<std::string_view> lines_of(std::string_view text) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = text.find('\n', start);
    out.push_back(text.substr(start, (end == std::string_view::npos ? text.size() : end) - start));
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return out;
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

// A '#' outside a string: a comment (good enough for the key = value lines of a profile).
bool has_comment(std::string_view line) {
  bool in_string = false;
  char quote = 0;
  for (const char c : line) {
    if (in_string) {
      if (c == quote) in_string = false;
    } else if (c == '"' || c == '\'') {
      in_string = true;
      quote = c;
    } else if (c == '#') {
      return true;
    }
  }
  return false;
}

// Whether the point whose table starts at or just before `line` (1-based: toml++ may give the
// header's line or its first key's) cites a source for its address: a comment on the address
// line or the line above it, or comment lines right above its [[point]] header.
bool cites(const std::vector<std::string_view>& lines, std::size_t line) {
  std::size_t header = std::min(line, lines.size());  // 1-based
  while (header > 1 && !trimmed(lines[header - 1]).starts_with("[[point]]")) --header;
  for (std::size_t i = header; i < lines.size(); ++i) {  // lines[header] follows the header
    const std::string_view t = trimmed(lines[i]);
    if (t.starts_with("[")) break;
    if (t.starts_with("address") && trimmed(t.substr(7)).starts_with("=")) {
      return has_comment(lines[i]) || (i > header && has_comment(lines[i - 1]));
    }
  }
  return header >= 2 && trimmed(lines[header - 2]).starts_with("#");
}

}  // namespace

ProfileReport check_profile(std::string_view text, const std::string& source,
                            std::span<const std::string_view> taken) {
  ProfileReport r;
  auto parsed = parse_profile(text, source);
  if (auto* errors = std::get_if<std::vector<std::string>>(&parsed)) {
    r.errors = std::move(*errors);
    return r;
  }
  const Profile& p = std::get<Profile>(parsed);
  r.errors = check_examples(p, source);
  const std::vector<bool> bound_points = p.bound_to_common();
  for (std::size_t i = 0; i < p.points.size(); ++i) {
    const ProfilePoint& pt = p.points[i];
    if (!bound_points[i] && std::find(taken.begin(), taken.end(), pt.name) != taken.end()) {
      r.errors.push_back(source + ":" + std::to_string(pt.line) + ": point.name: '" + pt.name +
                         "' is a name of the common block every device has "
                         "(docs/register-map.md): choose another");
    }
  }
  const CommonBindings& c = p.common;
  std::string missing;
  const auto need = [&](bool bound, const char* key) {
    // A binding the profile leaves out on purpose, saying why ([common] unbound), is no warning.
    if (!bound && !p.unbound.contains(key)) {
      missing += std::string(missing.empty() ? "" : ", ") + key;
    }
  };
  need(c.speed_rpm.has_value(), "speed_rpm");
  need(c.setpoint_rpm.has_value(), "setpoint_rpm");
  need(c.running.has_value(), "running");
  need(c.fault.has_value(), "fault");
  need(c.fault_code.has_value(), "fault_code");
  // A set value that runs the drive is its stop (0) and its run (the setpoint held).
  need(c.stop.has_value() || c.setpoint_runs, "stop");
  need(c.run_forward.has_value() || c.setpoint_runs, "run_forward");
  if (!missing.empty()) {
    r.warnings.push_back(source + ": common: not bound: " + missing +
                         " (the common block shows them unknown, a command refused)");
  }
  const auto lines = lines_of(text);
  for (const ProfilePoint& pt : p.points) {
    if (!cites(lines, pt.line)) {
      r.warnings.push_back(source + ":" + std::to_string(pt.line) + ": point: '" + pt.name +
                           "' cites no source for its address (a '#' comment on the address's "
                           "line or above it: document, edition, page or table)");
    }
  }
  return r;
}

}  // namespace drivegate::modbus_device
