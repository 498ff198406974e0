// One device as the bus engine sees it: the line side of its driver, wrapped by the device that
// owns it (gateway/device.h), so that every call the engine makes also publishes the device's
// state and settles its writes. The engine never calls a Driver directly.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "drivegate/driver.h"
#include "line/link.h"

namespace drivegate {

class Station {
 public:
  virtual ~Station() = default;

  [[nodiscard]] virtual const std::string& name() const = 0;
  // Its health, counters and policy, which the engine keeps up to date.
  virtual Link& link() = 0;
  // Writes wait for the line: the engine serves such a device before the polls.
  [[nodiscard]] virtual bool has_pending_writes() const = 0;
  // `kick` is called whenever something new is due (a write was queued); nullptr detaches.
  virtual void on_work(std::function<void()> kick) = 0;

  // The driver's line side (include/drivegate/driver.h).
  virtual std::optional<Exchange> next_exchange(TimePoint now) = 0;
  [[nodiscard]] virtual TimePoint wake_at() const = 0;
  virtual RxVerdict on_receive(ByteView rx, TimePoint now) = 0;
  virtual void on_no_reply(TimePoint now) = 0;
  // The engine declared comm_lost.
  virtual void on_comm_lost(TimePoint now) = 0;
  // The engine's periodic tick (kTickPeriod), line up or down: write deadlines, failsafe.
  virtual void on_tick(TimePoint now) = 0;
};

}  // namespace drivegate
