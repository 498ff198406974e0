// The write contract of include/drivegate/driver.h, checked the same way for every adapter. The
// gateway asks check() about a whole request, then applies its parts one at a time, each once the
// one before it settled (daemon/gateway/device_writes.cpp), so:
//   - check(request) says ok exactly when apply() then takes every part in order, and otherwise
//     what apply() says of the first part it refuses;
//   - check() has no side effect: the driver publishes the same (common(), values(), wake_at()),
//     completes nothing, and the line carries the same from then on.
// An adapter's contract_test.cpp names the states a request may find its driver in and the
// requests worth trying; the rest is here.
//
//   const auto tally = test::expect_check_is_apply(states(), requests());
//   EXPECT_TRUE(tally.ended_by_device.empty());
//   test::expect_check_has_no_side_effects(states(), requests(), /*turns=*/80);
#pragma once

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <memory>
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

// A state for each (state, name): a default-made `Hand` brought into it by `bring(hand, state)`.
template <class Hand, class State>
std::vector<WriteState> write_states(std::initializer_list<std::pair<State, const char*>> states,
                                     void (*bring)(Hand&, State)) {
  std::vector<WriteState> out;
  for (const auto& [state, name] : states) {
    out.push_back({name, [bring, s = state]() -> std::unique_ptr<DriverByHand> {
                     auto h = std::make_unique<Hand>();
                     bring(*h, s);
                     return h;
                   }});
  }
  return out;
}

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
