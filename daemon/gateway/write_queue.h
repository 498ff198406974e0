// The writes in flight at one device (docs/safety.md, "Fair line time"): each request's parts,
// whom it answers, where it stands, and what the device handed its driver since the line last
// asked it for an exchange. Bookkeeping only, no driver, no logging: the Device validates, asks
// the driver, settles and answers (device_writes.cpp); this says which request is where, and
// refuses a step its state does not allow.
//
// A request (WriteRequest::State), from push() until remove():
//
//   queued ---- a part handed to the driver, pending (handed) ------> carried
//   carried --- its part confirmed, parts still to apply (confirmed) -> between
//   between --- the next part handed, pending (handed) -------------> carried
//   any ------- done, failed, past its deadline, dropped (remove) ---> gone
//
//   Parts the driver takes at once (WriteStatus::done, the heartbeat) move `next` on without a
//   transition; a request whose every part went so is removed. Only a queued request may join an
//   equal one (coalesced) or be dropped by a stop before it; only a carried one waits on a ticket;
//   a stop (urgent) is never between at rest: its next part is handed as soon as one is confirmed.
//
// What the driver holds that the line has not carried yet (Handed), since its last next_exchange:
//
//   nothing --handed(part)--> part --handed(stop)--> part_and_stop
//   nothing --handed(stop)--> stop --handed(part)--> part_and_stop
//   any --exchanged()--> nothing, and LastExchange becomes wrote (it was not nothing) or polled
//   stop --forget_stops()--> nothing, part_and_stop --forget_stops()--> part (every request failed)
//
// pending() says the engine what it owes the device (a stop handed: urgent); may_release() whether
// a queued part may go to the driver outside a write turn (not after a write while a poll is due).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "bus/station.h"
#include "drivegate/driver.h"
#include "gateway/outcome.h"
#include "gateway/register_map.h"
#include "gateway/session.h"
#include "history/command_audit.h"

namespace drivegate {

// Writes waiting at one device, the one being carried out included (docs/safety.md, "Fair line
// time"): past it a write is refused at once (busy). Stops have as many places again of their
// own, so a full queue never holds one back, and so have a pass-through device's forwarded
// reads, so that read clients never get a write refused busy.
inline constexpr std::size_t kMaxQueuedWrites = 4;

// What happened to the writes a device was asked for, beyond what the line counters say.
struct WriteStats {
  std::uint64_t busy = 0;              // refused at once (busy): the queue was full
  std::uint64_t coalesced = 0;         // identical to the one waiting before it: answered with it
  std::uint64_t refused_failsafe = 0;  // a run from a source that cannot clear a latched failsafe
};

// One point of a write and the value it is to take, validated against the register map.
struct WritePart {
  const MappedPoint* point;
  Value value;
};

// Whom a request answers, and the audit record of that client's write in the making
// (history/command_audit.h): what it asked and when it was accepted.
struct WriteAnswer {
  WriteDone done;  // none for a forwarded request (WriteRequest::forward_done) or one answered
                   // at once
  CommandRecord record;
  TimePoint since;
  // When the client's last read of the drive's fault state, before it asked, showed a fault
  // (fault_reads.h); none if it showed none or the client cannot tell.
  std::optional<TimePoint> fault_seen;
  // Recorded (a write), counted only (the heartbeat alone, command_audit.h), or neither (a
  // forwarded read: not a write at all).
  enum class Audit : std::uint8_t { record, count, none };
  Audit audit = Audit::record;
  AccessLevel access = AccessLevel::read;  // the session's, to say why a write was denied
  // Taken by a request (queued, or joined to an equal one): the request records it when it
  // settles, not the entry that made it.
  bool taken = false;
};

// A write request in flight: its parts in the order they are applied, which part is next, the
// ticket of the part the driver is still carrying out, and when the client is answered
// no_response if it has not settled by then.
struct WriteRequest {
  enum class State : std::uint8_t { queued, carried, between };

  std::vector<WritePart> parts;  // the setpoint before the command
  std::size_t next = 0;          // the first part not applied yet
  // Queued: the latest it may start (never applied after). Started: when the part carried, or
  // the wait for the next write turn, has taken too long.
  TimePoint deadline;
  bool urgent = false;         // a stop, or the gateway's own: handed to the driver at once
  bool feeds_failsafe = true;  // from the PLC, and from a client whose writes prove it is there
  // A forwarded request that only reads (forward_access.h): it has places of its own in the
  // queue (WriteQueue::full), so that reads never fill a write's.
  bool reads_only = false;
  // Whom to answer: the client that asked, and any that asked the same while it waited.
  std::vector<WriteAnswer> answers;
  // A forwarded request (Device::forward) instead of parts: its PDU, whom to answer, and the
  // slave's reply once it came.
  std::optional<Bytes> forward;
  ForwardDone forward_done;
  Bytes reply;

  [[nodiscard]] State state() const { return state_; }
  // The ticket of the part the driver carries (state carried), none otherwise.
  [[nodiscard]] std::optional<Ticket> carried() const {
    return state_ == State::carried ? std::optional<Ticket>(ticket_) : std::nullopt;
  }
  [[nodiscard]] bool started() const { return state_ != State::queued; }
  // Every part (or the forwarded request) has been handed to the driver.
  [[nodiscard]] bool all_applied() const { return forward ? next > 0 : next == parts.size(); }

 private:
  friend class WriteQueue;
  State state_ = State::queued;
  Ticket ticket_ = 0;
};

class WriteQueue {
 public:
  enum class Handed : std::uint8_t { nothing, part, stop, part_and_stop };
  enum class LastExchange : std::uint8_t { polled, wrote };

  // `write_timeout`: how long a request may wait, and each part be carried, before it is late.
  explicit WriteQueue(Millis write_timeout) : write_timeout_(write_timeout) {}

  // --- the requests ---
  // Takes `r` in, queued, due by now + the write timeout.
  WriteRequest& push(std::unique_ptr<WriteRequest> r, TimePoint now);
  // A fresh ticket for a part handed to the driver.
  Ticket ticket() { return next_ticket_++; }
  // queued or between -> carried: the driver holds `r`'s part `t`, pending; it is due by now +
  // the write timeout. False (nothing changes) from carried.
  bool handed(WriteRequest& r, Ticket t, TimePoint now);
  // carried -> between: the part carried was confirmed and parts remain; the next is due by now
  // + the write timeout. False (nothing changes) from queued or between.
  bool confirmed(WriteRequest& r, TimePoint now);
  // Gone: the request leaves the queue (done, failed, late, dropped); null if it was not in it.
  std::unique_ptr<WriteRequest> remove(const WriteRequest* r);
  // Every request leaves the queue (comm lost, shutdown): the stops handed are forgotten.
  std::vector<std::unique_ptr<WriteRequest>> take_all();

  // The request whose part `t` the driver carries, if it is still here.
  [[nodiscard]] WriteRequest* carrying(Ticket t) const;
  // The oldest request that is not a stop: the only one of them the driver may be carrying out.
  [[nodiscard]] WriteRequest* head() const;
  // The newest request that is not a stop, if it has not started: an equal one may join it.
  [[nodiscard]] WriteRequest* last_queued() const;
  // Whether a new request of this kind must be refused busy: kMaxQueuedWrites places each for
  // stops, other writes and forwarded reads.
  [[nodiscard]] bool full(bool urgent, bool reads_only = false) const;
  [[nodiscard]] std::size_t size() const { return requests_.size(); }
  [[nodiscard]] bool empty() const { return requests_.empty(); }
  // The requests in flight, oldest first.
  [[nodiscard]] std::span<const std::unique_ptr<WriteRequest>> requests() const {
    return requests_;
  }

  // --- the line ---
  // The driver was asked for its next exchange: what was handed is on its way.
  void exchanged();
  [[nodiscard]] Handed handed_since() const { return handed_; }
  [[nodiscard]] LastExchange last_exchange() const { return last_; }
  // A queued part may go to the driver outside a write turn unless the device's last exchange
  // carried a write and a poll of its own is now due (`poll_due`): then that poll goes first.
  [[nodiscard]] bool may_release(bool poll_due) const {
    return last_ == LastExchange::polled || !poll_due;
  }
  // What the device asks of the line. `driver_due`: the driver wants the line now (a part it
  // carries is resent each turn until confirmed or its deadline passes, even while backed off).
  [[nodiscard]] PendingWrites pending(bool driver_due) const;

 private:
  Millis write_timeout_;
  Ticket next_ticket_ = 1;
  // In flight, oldest first: stops (urgent) are handed to the driver at once, the others one at
  // a time, oldest first, each part on a write turn the bus engine gives (Device::release).
  std::vector<std::unique_ptr<WriteRequest>> requests_;
  Handed handed_ = Handed::nothing;
  LastExchange last_ = LastExchange::polled;
};

}  // namespace drivegate
