// One device as the bus engine sees it: the line side of its driver, wrapped by the device that
// owns it (gateway/device.h), so that every call the engine makes also publishes the device's
// state and settles its writes. The engine never calls a Driver directly.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "bus/link.h"
#include "drivegate/driver.h"

namespace drivegate {

// What the engine gives a device the line for (bus_engine.h, "Fair line time").
enum class Turn : std::uint8_t {
  poll,   // the device's own traffic (polls, keep-alives): no new write is handed to the driver
  write,  // the next part of the device's oldest write is handed to its driver and sent
};

// What a device has for a write turn.
enum class PendingWrites : std::uint8_t {
  none,
  waiting,  // a Modbus write waits for a write turn
  urgent,   // a stop (the failsafe's, shutdown's or a client's) is with the driver: served first
};

class Station {
 public:
  virtual ~Station() = default;

  [[nodiscard]] virtual const std::string& name() const = 0;
  // Its health, counters and policy, which the engine keeps up to date.
  virtual Link& link() = 0;
  // Writes wait for the line: the engine gives such a device write turns, alternating with the
  // polls of the line (urgent ones first).
  [[nodiscard]] virtual PendingWrites pending_writes(TimePoint now) const = 0;
  // `kick` is called whenever something new is due (a write was queued); nullptr detaches.
  virtual void on_work(std::function<void()> kick) = 0;

  // The driver's line side (include/drivegate/driver.h). On a write turn the device hands its
  // driver the next part of its oldest write first.
  virtual std::optional<Exchange> next_exchange(TimePoint now, Turn turn) = 0;
  [[nodiscard]] virtual TimePoint wake_at() const = 0;
  // When the drive's state it now publishes was read whole, after a reply that carried state:
  // `now`, unless its driver reads the state in parts (Driver::state_read_at).
  [[nodiscard]] virtual std::optional<TimePoint> state_read_at(TimePoint now) const { return now; }
  virtual RxVerdict on_receive(ByteView rx, TimePoint now) = 0;
  virtual void on_no_reply(TimePoint now) = 0;
  // The engine declared comm_lost.
  virtual void on_comm_lost(TimePoint now) = 0;
  // The engine's periodic tick (kTickPeriod), line up or down: write deadlines, failsafe.
  virtual void on_tick(TimePoint now) = 0;
};

}  // namespace drivegate
