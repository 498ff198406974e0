// `drivegate profile check` without the command line: a profile's text linted as the library test
// lints every shipped one. Errors: everything parse_profile() refuses (file and line: overlaps,
// points wider than [modbus] max_registers...) and every [[example]] the profile contradicts.
// Warnings: a common block left partly unbound, and a point whose address cites no source (a
// heuristic: no '#' comment on the address's line or the one above it, nor in the comment lines
// right above its [[point]]). `taken`: the names a device's register map has before the
// profile's points (the common block's, which the daemon owns: the CLI passes them); a point of
// the device's own (not bound to the common block) that takes one is an error, as the daemon
// refuses such a device. Pure.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate::modbus_device {

struct ProfileReport {
  std::vector<std::string> errors;    // "SOURCE:LINE: key: what"
  std::vector<std::string> warnings;  // the same form
};

ProfileReport check_profile(std::string_view text, const std::string& source,
                            std::span<const std::string_view> taken = {});

}  // namespace drivegate::modbus_device
