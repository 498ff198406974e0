// Options for the ed3100 tests: the schema's defaults, as the gateway would fill them in.
#pragma once

#include <map>
#include <string>

#include "drivegate/options.h"

namespace drivegate::ed3100::test {

inline Options options(std::map<std::string, OptionValue, std::less<>> overrides = {}) {
  std::map<std::string, OptionValue, std::less<>> v = {
      {"poles", std::int64_t{4}},
      {"monitors", std::vector<std::string>{"0D00:Hz", "0D01", "0D02", "0D03"}},
      {"speed_monitor", std::string("0D00")},
      {"parameters", std::vector<std::string>{}},
      {"frame_gap_ms", std::int64_t{10}},
      {"timeout_ms", std::int64_t{100}},
      {"attempts", std::int64_t{3}},
      {"comm_timeout_ms", std::int64_t{3000}},
      {"reset_register", std::int64_t{0x2002}},
      {"reset_value", std::int64_t{2}},
      {"sim_reply_form", std::string("document")},
  };
  for (auto& [k, x] : overrides) v[k] = x;
  return Options(std::move(v));
}

}  // namespace drivegate::ed3100::test
