// What one client has seen of each drive's faults: when its last read of a drive's fault state
// (the common block's status, fault_code or fault_mask, or the fault status bit) showed a fault.
// The client's next write is stamped with it (WriteOp::fault_seen): a run asked by a client that
// had read the trip is its choice made with the trip in view, one asked without it is not
// (adapters/modbus/driver_writes.cpp, set-value fans). Not when the request arrived: a run sent
// before the trip but read from the socket after it was not asked with the trip in view.
//
// A read counts once the client can have read its reply, and only for what the client sends
// after that: served (the gateway answered it), then sent (its reply went out), then seen (the
// client sent more bytes since). A run sent in the same segment as the read before it (a
// pipelining client), or after a read whose reply was dropped (the serial master had already
// given up, or the line went), was decided without that reply. A run sent before the reply
// arrived but read from the socket later (a second TLS record or packet) cannot be told from one
// sent after it: the gateway takes it as read (docs/profiles.md says what else it cannot tell).
//
// One per connection (a Modbus TCP / TLS client, a serial listener's line, an RTU-over-TCP
// client); none for a northbound that cannot tell what its client read (MQTT: a DDATA is
// published, not known to be read), whose runs then count as asked before any trip. Single-
// threaded, as the gateway is. Header-only, in dg_gateway_api with session.h.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <vector>

namespace drivegate {

class FaultReads {
 public:
  using TimePoint = std::chrono::steady_clock::time_point;

  // Drives whose fault this client has seen and not read gone since, kept at most: a drive
  // removed by a reload leaves its entry; the oldest goes first past the bound.
  static constexpr std::size_t kMaxDrives = 256;
  // Reads served whose replies have not gone out, or that the client has not answered since,
  // kept at most (a client that pipelines without reading its replies): the oldest is forgotten
  // first, which can only withhold an exemption (a forgotten "none" leaves a fault seen earlier,
  // older than any trip after it).
  static constexpr std::size_t kMaxInFlight = 1024;

  // The gateway served the client a read of `drive`'s fault state at `now`, showing a fault or
  // not (which, once seen, forgets the fault seen before: a later trip is one not read).
  void served(const void* drive, bool shows_fault, TimePoint now) {
    if (in_flight_.size() == kMaxInFlight) {
      in_flight_.pop_front();
      if (sent_ > 0) --sent_;
    }
    in_flight_.push_back({served_count_++, drive, shows_fault, now});
  }
  // Reads served so far: a mark for sent().
  [[nodiscard]] std::uint64_t served_count() const { return served_count_; }
  // The replies of the reads served before `mark` (a served_count()) have gone out.
  void sent(std::uint64_t mark) {
    const auto end = std::partition_point(in_flight_.begin(), in_flight_.end(),
                                          [mark](const InFlight& r) { return r.seq < mark; });
    sent_ = std::max(sent_, static_cast<std::size_t>(end - in_flight_.begin()));
  }
  // Every read served so far has had its reply go out (a reply sent as soon as it is made).
  void all_sent() { sent_ = in_flight_.size(); }
  // The replies of the reads served and not sent will never go out (dropped): they never count.
  void unsent_dropped() { in_flight_.resize(sent_); }
  // The line went: a reply handed to it may not have gone out either. Nothing served before
  // counts.
  void forget_in_flight() {
    in_flight_.clear();
    sent_ = 0;
  }
  // The client sent more: the reads whose replies went out before count from now on.
  void received() {
    for (std::size_t i = 0; i < sent_; ++i) {
      const InFlight& r = in_flight_.front();
      seen(r.drive, r.shows_fault, r.at);
      in_flight_.pop_front();
    }
    sent_ = 0;
  }

  // When the client's last read of `drive`'s fault state that counts showed a fault; none if it
  // showed none or the client never read it. A drive's identity is its address: an entry of a
  // drive removed by a reload is older than anything its successor at the same address shows, so
  // it never counts as that one's trip seen.
  [[nodiscard]] std::optional<TimePoint> fault_seen(const void* drive) const {
    const auto it = std::find_if(seen_.begin(), seen_.end(),
                                 [drive](const Seen& e) { return e.drive == drive; });
    if (it == seen_.end()) return std::nullopt;
    return it->at;
  }

 private:
  struct InFlight {
    std::uint64_t seq;  // its served_count() before it
    const void* drive;
    bool shows_fault;
    TimePoint at;
  };
  struct Seen {
    const void* drive;
    TimePoint at;
  };

  void seen(const void* drive, bool shows_fault, TimePoint at) {
    const auto it = std::find_if(seen_.begin(), seen_.end(),
                                 [drive](const Seen& e) { return e.drive == drive; });
    if (!shows_fault) {
      if (it != seen_.end()) seen_.erase(it);
      return;
    }
    if (it != seen_.end()) {
      it->at = at;
      return;
    }
    if (seen_.size() == kMaxDrives) {
      seen_.erase(std::min_element(seen_.begin(), seen_.end(),
                                   [](const Seen& a, const Seen& b) { return a.at < b.at; }));
    }
    seen_.push_back({drive, at});
  }

  std::deque<InFlight> in_flight_;  // served, oldest first; the first sent_ of them have gone out
  std::size_t sent_ = 0;
  std::uint64_t served_count_ = 0;
  std::vector<Seen> seen_;
};

}  // namespace drivegate
