// A profile's examples ([[example]]): frames the device's manual prints, and the values of the
// profile's points they carry. Read from the profile's TOML here; check_examples() holds the
// profile to them: a read's reply decodes, as the profile decodes it, to the values expected, a
// write of the expected values is the request's data, and every frame's CRC (or LRC) is good.
// Pure: `drivegate profile check` and the tests call the same function.
#pragma once

#include <string>
#include <vector>

#include "drivegate/toml_reader.h"
#include "profile.h"

namespace drivegate::modbus_device {

// Every [[example]] of `root` into profile.examples (after the points: `expect` names them),
// errors into `diag`.
void read_profile_examples(const toml::table& root, TableReader& top, Diagnostics& diag,
                           Profile& profile);

// The frame an example's text stands for: hex bytes ("01 04 08 38 00 01 B3 A6", spaces
// optional) for RTU, the frame's characters (":010300...", CR LF added when missing) for ASCII;
// nothing when the text is neither.
std::optional<Bytes> example_frame(const Profile& profile, const std::string& text);

// What is wrong with `example` for `profile`: nothing when the profile agrees with it.
std::vector<std::string> check_example(const Profile& profile, const ProfileExample& example);

// Every example's problems, each "SOURCE:LINE: example: what", as parse errors read.
std::vector<std::string> check_examples(const Profile& profile, const std::string& source);

}  // namespace drivegate::modbus_device
