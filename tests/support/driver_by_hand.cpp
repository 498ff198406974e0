#include "driver_by_hand.h"

#include <algorithm>
#include <utility>

namespace drivegate::test {

std::optional<WriteResult> DriverByHand::settle(Ticket t, int turns) {
  for (int i = 0;; ++i) {
    d->take_completions(done_);
    const auto it = std::find_if(done_.begin(), done_.end(),
                                 [t](const Completion& c) { return c.ticket == t; });
    if (it != done_.end()) {
      const WriteResult result = it->result;
      done_.erase(it);
      return result;
    }
    if (i == turns || !turn()) return std::nullopt;
  }
}

std::vector<Completion> DriverByHand::completions() {
  d->take_completions(done_);
  return std::exchange(done_, {});
}

}  // namespace drivegate::test
