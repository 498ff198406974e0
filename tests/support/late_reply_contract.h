// What every request / reply adapter must do with a drive that answers after its reply timeout
// (docs/safety.md, "Late replies"), checked the same way for each on the real bus engine with a
// simulated clock (the test is in late_reply_contract_test.cpp, which every adapter's test binary
// compiles). The adapter's driver_test.cpp states how late is late for its protocol and
// instantiates the test in one line:
//
//   const test::LateReplyFacts kLate{.id = "ed3100", .late = 130ms, .sim_commands = {...}};
//   INSTANTIATE_TEST_SUITE_P(Ed3100, LateReplyContract, testing::Values(kLate));
//
// A streaming adapter (fdc1), whose status is not a reply, states its own test instead.
#pragma once

#include <gtest/gtest.h>

#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "bus_rig.h"

namespace drivegate::test {

struct LateReplyFacts {
  std::string_view id;
  Millis late;  // the simulator's turnaround: past the device's reply timeout
  OptionText options;                     // the device's and the simulator's
  std::vector<std::string> sim_commands;  // operator commands first (an ED3100's reply form)
};

inline void PrintTo(const LateReplyFacts& f, std::ostream* os) {
  *os << f.id << " " << f.late.count() << " ms late";
}

class LateReplyContract : public testing::TestWithParam<LateReplyFacts> {};

}  // namespace drivegate::test
