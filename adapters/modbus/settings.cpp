#include "settings.h"

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string_view>

#include "profile_options.h"

namespace drivegate::modbus_device {
namespace {

struct ShippedProfile {
  std::string_view name;
  std::string_view text;
};
#include "shipped_profiles.inc"

// The file's text; nullopt when there is none. A file that is there but cannot be used is an
// error (not a reason to look further), so a broken override never silently falls back.
std::optional<std::string> read_file(const std::string& path, std::string& error) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return std::nullopt;
  if (!S_ISREG(st.st_mode)) {
    error = path + " is not a regular file";
    return std::nullopt;
  }
  if (static_cast<std::size_t>(st.st_size) > kMaxProfileBytes) {
    error = path + " is larger than " + std::to_string(kMaxProfileBytes) + " bytes";
    return std::nullopt;
  }
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  if (!in) {
    error = "cannot read " + path;
    return std::nullopt;
  }
  return s.str();
}

}  // namespace

std::optional<ProfileText> find_profile(const std::string& name, std::string& error) {
  error.clear();
  if (name.find('/') != std::string::npos) {
    auto text = read_file(name, error);
    if (!text) {
      if (error.empty()) error = "no profile file " + name;
      return std::nullopt;
    }
    return ProfileText{std::move(*text), name};
  }
  if (!valid_profile_name(name)) {
    error = "'" + name + "' is neither a profile name (a-z, 0-9, '-', '_') nor a path";
    return std::nullopt;
  }
  for (const char* dir : kProfileDirs) {
    const std::string path = std::string(dir) + "/" + name + ".toml";
    auto text = read_file(path, error);
    if (text) return ProfileText{std::move(*text), path};
    if (!error.empty()) return std::nullopt;
  }
  for (const ShippedProfile& p : kShippedProfiles) {
    if (p.name == name) return ProfileText{std::string(p.text), "shipped " + name};
  }
  std::string known;
  for (const ShippedProfile& p : kShippedProfiles) {
    known += (known.empty() ? "" : ", ") + std::string(p.name);
  }
  error = "no profile '" + name + "' in " + kProfileDirs[0] + " or " + kProfileDirs[1] +
          " (shipped: " + known + ")";
  return std::nullopt;
}

std::string profile_read(const ProfileText& profile) {
  // FNV-1a 64 (Fowler, Noll, Vo): offset basis 0xcbf29ce484222325, prime 0x100000001b3.
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const char c : profile.text) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return "profile " + profile.source + " (content " + hex + ")";
}

std::vector<std::string_view> shipped_profile_names() {
  std::vector<std::string_view> names;
  names.reserve(std::size(kShippedProfiles));
  for (const ShippedProfile& p : kShippedProfiles) names.push_back(p.name);
  return names;
}

std::optional<Settings> parse_settings(const Options& options, std::string& error, Unset unset) {
  Settings s;
  auto text = find_profile(options.string("profile"), error);
  if (!text) {
    error = "option profile: " + error;
    return std::nullopt;
  }
  auto parsed = parse_profile(text->text, text->source);
  if (auto* errors = std::get_if<std::vector<std::string>>(&parsed)) {
    // Every error, so the profile is fixed in one pass; one line, as a factory's error is.
    error = "option profile:";
    for (const auto& e : *errors) error += (&e == &errors->front() ? " " : "; ") + e;
    return std::nullopt;
  }
  s.profile = std::get<Profile>(std::move(parsed));
  // The profile's own options ([options.NAME]), as the device sets them.
  if (!apply_options(s.profile, options, error, unset)) return std::nullopt;
  s.files_read = profile_read(*text);
  s.profile_source = std::move(text->source);
  s.attempts = static_cast<std::uint8_t>(options.integer("attempts"));
  s.comm_timeout = Millis(options.integer("comm_timeout_ms"));
  return s;
}

namespace {

std::string describe(std::uint32_t baud, Parity parity, unsigned data_bits, unsigned stop_bits) {
  return std::to_string(baud) + " baud, " + std::to_string(data_bits) + " data bits, " +
         std::string(to_string(parity)) + " parity, " + std::to_string(stop_bits) + " stop bit" +
         (stop_bits == 1 ? "" : "s");
}

}  // namespace

bool line_agrees(const Profile& profile, const std::string& source, const LineDefaults& bus,
                 std::string& error) {
  const LineSpec& want = profile.line;
  // RTU carries 8 data bits (Serial Line 2.5.1); ASCII 7 by the specification, 8 by many devices.
  const bool bits_ok = want.framing == Framing::rtu ? bus.data_bits == 8 : true;
  if (bus.baud == want.baud && bus.parity == want.parity && bus.stop_bits == want.stop_bits &&
      bits_ok) {
    return true;
  }
  error = "option profile: " + source + " says [line] " +
          describe(want.baud, want.parity, want.framing == Framing::rtu ? 8 : bus.data_bits,
                   want.stop_bits) +
          ", but the bus runs " + describe(bus.baud, bus.parity, bus.data_bits, bus.stop_bits) +
          ": set the [[bus]] to the device's line (or correct the profile)";
  return false;
}

std::optional<PassthroughSettings> parse_passthrough(const Options& options, std::string& error) {
  if (!options.boolean("passthrough")) {
    error = "option passthrough: false";
    return std::nullopt;
  }
  // The schema's default is the only profile a pass-through device may carry: one named beside
  // passthrough would be silently unused.
  if (options.string("profile") != kDefaultProfile) {
    error =
        "option profile: a pass-through device reads no profile (it forwards every request "
        "as it is): remove profile or passthrough";
    return std::nullopt;
  }
  PassthroughSettings s;
  s.framing = options.string("framing") == "ascii" ? Framing::ascii : Framing::rtu;
  s.reply_timeout = Millis(options.integer("timeout_ms"));
  s.attempts = static_cast<std::uint8_t>(options.integer("attempts"));
  s.comm_timeout = Millis(options.integer("comm_timeout_ms"));
  return s;
}

std::optional<std::uint8_t> device_address(std::uint32_t address, std::string& error) {
  if (address < 1 || address > kMaxSlave) {
    error = "address " + std::to_string(address) + ": a Modbus slave is 1..247";
    return std::nullopt;
  }
  return static_cast<std::uint8_t>(address);
}

}  // namespace drivegate::modbus_device
