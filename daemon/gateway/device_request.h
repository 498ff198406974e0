// A Modbus write request in flight at one device (device_writes.cpp): its parts in the order they
// are applied, which part is next, the ticket of the part the driver is still carrying out, and
// when the PLC is answered 0x0B if that part has not settled by then.
#pragma once

#include <optional>
#include <vector>

#include "gateway/device.h"

namespace drivegate {

struct Device::Request {
  std::vector<Part> parts;  // the setpoint before the command
  std::size_t next = 0;     // the first part not applied yet
  std::optional<Ticket> waiting;
  TimePoint deadline;  // of the part in `waiting`
  bool feeds_failsafe = true;  // from the PLC, and from a client whose writes prove it is there
  modbus::WriteDone done;
};

}  // namespace drivegate
