// A write request in flight at one device (device_writes.cpp): its parts in the order they are
// applied, which part is next, the ticket of the part the driver is still carrying out, and when
// the client is answered no_response if it has not settled by then.
#pragma once

#include <optional>
#include <vector>

#include "gateway/device.h"

namespace drivegate {

// Whom a request answers, and the audit record of that client's write in the making
// (history/command_audit.h): what it asked and when it was accepted.
struct Device::Answer {
  WriteDone done;  // none for a forwarded request (Request::forward_done) or one answered at once
  CommandRecord record;
  TimePoint since;
  // Recorded (a write), counted only (the heartbeat alone, command_audit.h), or neither (a
  // forwarded read: not a write at all).
  enum class Audit : std::uint8_t { record, count, none };
  Audit audit = Audit::record;
  AccessLevel access = AccessLevel::read;  // the session's, to say why a write was denied
  // Taken by a request (queued, or joined to an equal one): the request records it when it
  // settles, not the entry that made it.
  bool taken = false;
};

struct Device::Request {
  std::vector<Part> parts;  // the setpoint before the command
  std::size_t next = 0;     // the first part not applied yet
  std::optional<Ticket> waiting;
  // Queued: the latest it may start (never applied after). Started: when the part in `waiting`,
  // or the wait for the next write turn, has taken too long.
  TimePoint deadline;
  bool urgent = false;         // a stop, or the gateway's own: handed to the driver at once
  bool feeds_failsafe = true;  // from the PLC, and from a client whose writes prove it is there
  // A forwarded request that only reads (forward_access.h): it has places of its own in the
  // queue (Device::queued), so that reads never fill a write's.
  bool reads_only = false;
  // Whom to answer: the client that asked, and any that asked the same while it waited.
  std::vector<Answer> answers;
  // A forwarded request (Device::forward) instead of parts: its PDU, whom to answer, and the
  // slave's reply once it came.
  std::optional<Bytes> forward;
  ForwardDone forward_done;
  Bytes reply;

  [[nodiscard]] bool started() const { return next > 0; }
  // Every part (or the forwarded request) has been handed to the driver.
  [[nodiscard]] bool all_applied() const { return forward ? next > 0 : next == parts.size(); }
};

}  // namespace drivegate
