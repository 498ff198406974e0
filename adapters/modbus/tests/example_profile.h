// The shipped profiles as the tests read them: adapters/modbus/profiles/ (DRIVEGATE_PROFILE_DIR),
// and the reader of a profile's file the tests' own profiles share (profile_support.h).
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <variant>

#include "profile.h"

namespace drivegate::modbus_device {

// The text of the profile `dir`/<name>.toml.
inline std::string profile_text(const std::string& dir, const std::string& name) {
  std::ifstream in(dir + "/" + name + ".toml");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace drivegate::modbus_device

namespace drivegate::modbus_device::shipped {

// The text of profiles/<name>.toml.
inline std::string text(const std::string& name) {
  return profile_text(DRIVEGATE_PROFILE_DIR, name);
}

// The example, parsed (its tests in profile_test.cpp say it parses).
inline Profile example() {
  auto r = parse_profile(text("example-vfd"), "example-vfd.toml");
  return std::get<Profile>(std::move(r));
}

}  // namespace drivegate::modbus_device::shipped
