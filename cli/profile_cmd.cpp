// drivegate profile check: Modbus device profiles (docs/profiles.md) linted without a
// configuration, as the library test lints the shipped ones: every error FILE:LINE: key: what,
// then the warnings. The modbus adapter's library does the work (profile_check.h); this file
// reads the command line and the files. Exit 0: clean (warnings allowed unless --strict), 1:
// errors, 2: usage.
#include <filesystem>
#include <iostream>

#include "commands.h"
#include "gateway/register_map.h"
#include "modbus/profile_check.h"
#include "modbus/settings.h"

namespace drivegate::cli {

namespace {

constexpr Option kProfileOptions[] = {
    {"strict", 0, nullptr, "warnings count as errors (exit 1)"},
    kHelpOption,
};

constexpr const char* kProfileAbout =
    "Checks Modbus device profiles (a path, or a name found as a device finds it):\n"
    "  check FILE...  every parse error (FILE:LINE: key: what), overlapping points, points\n"
    "                 wider than [modbus] max_registers, [[example]] frames the profile\n"
    "                 contradicts, point names the common block has; warnings for a common\n"
    "                 block left partly unbound and for points whose address cites no\n"
    "                 source.\n"
    "Exit status: 0 clean, 1 errors (or warnings with --strict), 2 usage. See docs/profiles.md.";

}  // namespace

int profile(std::span<const std::string> args) {
  const CommandLine cli("drivegate profile", kProfileOptions, {"check [--strict] FILE..."},
                        kProfileAbout);
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  const auto& ops = parsed->operands;
  if (ops.empty()) return cli.usage_error("which use? (check)");
  if (ops[0] != "check") return cli.usage_error("no such use '" + ops[0] + "' (check)");
  if (ops.size() < 2) return cli.usage_error("check needs one or more profiles: paths or names");
  const bool strict = parsed->has("strict");
  // The names every device's register map has before its adapter's points: the daemon refuses a
  // device whose profile gives a point one of them.
  const RegisterMap common_only({});
  std::vector<std::string_view> taken;
  for (const MappedPoint& p : common_only.points()) taken.emplace_back(p.spec.name);
  bool failed = false;
  for (std::size_t i = 1; i < ops.size(); ++i) {
    std::string error;
    // A file here is a path even without a '/' (a device's option would take it for a name).
    const bool here = ops[i].find('/') == std::string::npos && std::filesystem::exists(ops[i]);
    const auto text = modbus_device::find_profile(here ? "./" + ops[i] : ops[i], error);
    if (!text) {
      std::cerr << "drivegate profile: " << error << "\n";
      failed = true;
      continue;
    }
    const auto report = modbus_device::check_profile(text->text, text->source, taken);
    for (const auto& e : report.errors) std::cout << e << "\n";
    for (const auto& w : report.warnings) std::cout << "warning: " << w << "\n";
    failed = failed || !report.errors.empty() || (strict && !report.warnings.empty());
    if (report.errors.empty() && report.warnings.empty()) {
      std::cout << text->source << ": ok\n";
    }
  }
  return failed ? 1 : 0;
}

}  // namespace drivegate::cli
