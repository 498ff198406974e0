// The write contract (write_contract.h) as a suite a request / reply adapter instantiates with
// its states and requests in its contract_test.cpp.
#include "write_contract.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace drivegate::test {
namespace {

// Compiled into every adapter's test program (dg_adapter_contracts); fdc1, modbus and framed keep
// their own write checks and instantiate nothing.
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(WriteContract);

TEST_P(WriteContract, CheckAcceptsARequestExactlyWhenApplyTakesItsPartsInOrder) {
  const WriteContractCase& c = GetParam();
  const ContractTally tally = expect_check_is_apply(c.states(), c.requests());
  if (!c.device_refuses_anywhere) {
    for (const EndedByDevice& ended : tally.ended_by_device) {
      const bool allowed =
          std::any_of(c.device_refuses_in.begin(), c.device_refuses_in.end(),
                      [&](const std::string& prefix) { return ended.state.starts_with(prefix); });
      EXPECT_TRUE(allowed) << "the device failed a part in state " << ended.state << ": "
                           << ended.request;
    }
  }
  EXPECT_GE(tally.judged, c.min_judged);
  EXPECT_GE(tally.compared, c.min_compared);
}

TEST_P(WriteContract, CheckHasNoSideEffects) {
  const WriteContractCase& c = GetParam();
  expect_check_has_no_side_effects(c.states(), c.requests(), c.turns);
}

}  // namespace
}  // namespace drivegate::test
