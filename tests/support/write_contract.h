// The write contract of include/drivegate/driver.h, checked the same way for every adapter. The
// gateway asks check() about a whole request, then applies its parts one at a time, each once the
// one before it settled (daemon/gateway/device_writes.cpp), so:
//   - check(request) says ok exactly when apply() then takes every part in order, and otherwise
//     what apply() says of the first part it refuses;
//   - check() has no side effect: the driver publishes the same (common(), values(), wake_at()),
//     completes nothing, and the line carries the same from then on.
// An adapter's contract_test.cpp names the states a request may find its driver in and the
// requests worth trying, and instantiates the suite WriteContract with them in one line (the
// tests are in write_contract_test.cpp, which the adapter's test binary compiles); the rest is
// here.
//
//   INSTANTIATE_TEST_SUITE_P(Mdriver, WriteContract,
//                            testing::Values(test::WriteContractCase{
//                                .name = "mdriver", .states = states, .requests = requests,
//                                .turns = 60}));
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "driver_by_hand.h"

namespace drivegate::test {

using Request = std::vector<WriteOp>;

// A state a request may find the driver in: a name for the failure messages, and a fresh driver
// brought into it (fatal failures on the way end the check).
struct WriteState {
  std::string name;
  std::function<std::unique_ptr<DriverByHand>()> make;
};

// A state for each of `State`'s enumerators in their order from 0, named by `names` in the same
// order: a default-made `Hand` brought into it by `bring(hand, state)`.
template <class Hand, class State>
std::vector<WriteState> write_states(void (*bring)(Hand&, State),
                                     std::initializer_list<const char*> names) {
  std::vector<WriteState> out;
  int index = 0;
  for (const char* name : names) {
    out.push_back(
        {name, [bring, s = static_cast<State>(index++)]() -> std::unique_ptr<DriverByHand> {
           auto h = std::make_unique<Hand>();
           bring(*h, s);
           return h;
         }});
  }
  return out;
}

// For a state's bring(): "run forward" applied as the gateway applies it (pending), confirmed by
// the device (settled ok) and in force; or what was not.
testing::AssertionResult runs_forward(DriverByHand& h);

// The part applied last (h.ticket at `applied`), on the line and never answered, fails with
// no_response at the driver's own `deadline` and not a moment before: before the gateway's
// write_timeout would.
void expect_fails_at_own_deadline(DriverByHand& h, TimePoint applied, Millis deadline);

// What a PLC writing holding registers command and setpoint_rpm can ask: every command alone, and
// each setpoint alone and before every command.
std::vector<Request> command_requests(std::initializer_list<std::int32_t> setpoints);

// A request whose part the device failed after apply() took it (an alarm from the stream, an
// ACK with error bits): a verdict no check() can give in advance, so nothing was compared.
struct EndedByDevice {
  std::string state;
  std::string request;
};

struct ContractTally {
  int judged = 0;    // (state, request) pairs check() judged
  int compared = 0;  // of which the parts' outcome was known and compared with the verdict
  std::vector<EndedByDevice> ended_by_device;
};

// For every state and request, on a fresh driver: check() answers the same twice and changes
// nothing it publishes, then the parts are applied in order, each once the one before settled,
// and the verdict is compared with what apply() did.
ContractTally expect_check_is_apply(const std::vector<WriteState>& states,
                                    const std::vector<Request>& requests);

// For every state: a driver that judged every request against one that judged none publishes the
// same, has completed nothing, and sends the same for `turns` turns of the line.
void expect_check_has_no_side_effects(const std::vector<WriteState>& states,
                                      const std::vector<Request>& requests, int turns);

// One adapter's case of the suite WriteContract: expect_check_is_apply() and
// expect_check_has_no_side_effects() on its states and requests.
struct WriteContractCase {
  std::string name;
  std::function<std::vector<WriteState>()> states;
  std::function<std::vector<Request>()> requests;
  int turns = 60;  // turns of the line compared after check()
  // Where the device may fail a part apply() took (an alarm, a lock: a verdict no check() can
  // give in advance): the states whose names start with one of these. Empty: in none.
  std::vector<std::string> device_refuses_in;
  bool device_refuses_anywhere = false;  // in any state (an ACK's error bits)
  int min_judged = 0;                    // (state, request) pairs judged, at least
  int min_compared = 0;                  // of which compared with apply()'s outcome, at least
};

inline void PrintTo(const WriteContractCase& c, std::ostream* os) {
  *os << c.name;
}

class WriteContract : public testing::TestWithParam<WriteContractCase> {};

// "setpoint 2000; run_forward; point 3 = 1", for failure messages.
std::string describe(const Request& request);

// What a driver publishes, to compare before and after a call that must change nothing.
struct Published {
  CommonState common;
  std::vector<Value> values;
  TimePoint wake_at;
};
Published published(const Driver& d);
// Field by field, so that a failure names what differs.
void expect_same(const Published& a, const Published& b);

}  // namespace drivegate::test
