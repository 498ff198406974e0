// The daemon's history: the last events and commands (event.h), in bounded memory, on three
// shelves each with its own bound, so that what one kind of entry floods cannot push another
// out (docs/audit.md):
// - events: what happened to the plant (faults, comm lost, failsafe, drives started and stopped,
//   reloads, listeners, MQTT) and the gateway's own writes (the failsafe's, shutdown's,
//   on_start's), which no client can cause in a flood;
// - commands: the clients' writes carried out, which only a client with write rights can add;
// - refusals: the clients' writes refused, which anyone who can reach a port can add.
// Each keeps its newest `HistoryBounds` entries, the oldest dropped first (and counted); the
// sequence numbers run across the three, and a query reads them as one list in that order.
// Each entry's strings are cut at kMaxText bytes and it has at most kMaxFields fields (two more
// once it counts repeats), so an entry takes at most about 2 x (kMaxFields + 3) x kMaxText bytes
// (7.7 KB) whatever a client sends; a typical command entry takes about 0.8 KB (memory_bytes()
// counts them). Pure: the wall clock is injected.
//
// A repeat (the same command from the same client with the same result as the device's newest
// entry) updates that entry in place (its "repeats" and "last_ms" fields) instead of pushing
// anything out: a PLC that writes its command word every scan leaves one entry, and anything
// else that happens to the device in between still shows in its order. The device's newest entry
// is kept aside (one per device), so a repeat is known as such however many other devices wrote
// since, and with a capacity of 0 too.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "history/event.h"

namespace drivegate {

inline constexpr std::size_t kDefaultHistory = 2000;  // entries of each shelf kept by default
inline constexpr std::size_t kMaxText = 256;          // bytes of one message or field value
inline constexpr std::size_t kMaxFields = 12;         // fields of one entry as recorded
inline constexpr std::size_t kMaxQuery = 1000;        // entries one query returns at most

// The history's shelves (above), in the order of their names.
enum class Shelf : std::uint8_t { events, commands, refusals };
inline constexpr std::array<std::string_view, 3> kShelfNames = {"events", "commands", "refusals"};
constexpr std::string_view to_string(Shelf s) {
  return kShelfNames.at(static_cast<std::size_t>(s));
}
// The shelf an entry goes on: a command by its "source" and "result" fields, anything else on
// the events'.
Shelf shelf_of(const Event& e);

// How many entries each shelf keeps ([history] events, commands, refusals); 0: none.
struct HistoryBounds {
  std::size_t events = kDefaultHistory;
  std::size_t commands = kDefaultHistory;
  std::size_t refusals = kDefaultHistory;
  [[nodiscard]] std::size_t of(Shelf s) const {
    return s == Shelf::events ? events : s == Shelf::commands ? commands : refusals;
  }
};

// Which entries a query wants: all that match every criterion given; without `after_seq` the
// newest `limit` of them, with it the oldest `limit` after that one (a follower catching up).
struct EventFilter {
  std::string device;              // empty: any
  std::optional<EventKind> kind;   // none: any
  std::int64_t since_ms = 0;       // recorded at or after (ms since the epoch)
  std::uint64_t after_seq = 0;     // with a sequence number above (`drivegate events --follow`)
  std::size_t limit = 100;         // at most kMaxQuery
};

class EventLog {
 public:
  using WallClock = std::function<std::int64_t()>;  // milliseconds since the epoch
  static std::int64_t system_ms();

  explicit EventLog(HistoryBounds bounds = {}, WallClock wall = &system_ms);
  // `each` entries on every shelf; 0: nothing is kept (the audit trail still reaches the
  // journal).
  explicit EventLog(std::size_t each, WallClock wall = &system_ms);

  // Cuts `e` as the log keeps it (text at kMaxText on a character, fields at kMaxFields); add()
  // and repeat() do, so a caller may compare first.
  static void fit(Event& e);
  // Records `e` now (its seq and time are set here) and returns its seq.
  std::uint64_t add(Event e);
  // Whether `e` (fitted) repeats its device's newest entry: a command whose fields are all equal
  // but "took_ms". If so one more repeat is counted there, and `e` is not to be added.
  bool repeat(const Event& e);
  // Something happened to `device` that the log does not keep (a write folded into a summary,
  // command_fold.h): its newest entry is no longer what a repeat would repeat.
  void interrupt(std::string_view device);
  // The wall clock's time now.
  [[nodiscard]] std::int64_t now_ms() const { return wall_(); }

  // Matching entries of every shelf, in sequence, oldest first.
  [[nodiscard]] std::vector<Event> query(const EventFilter& filter) const;
  // The sequence numbers of the entries query() returns, without copying them.
  [[nodiscard]] std::vector<std::uint64_t> matching(const EventFilter& filter) const;
  // The entry with sequence number `seq`, while the log holds it (until the next add()).
  [[nodiscard]] const Event* find(std::uint64_t seq) const;
  [[nodiscard]] std::size_t size() const;
  [[nodiscard]] std::size_t capacity() const;
  [[nodiscard]] std::uint64_t last_seq() const { return next_seq_ - 1; }
  [[nodiscard]] std::uint64_t dropped() const;  // pushed out, oldest first, from any shelf
  [[nodiscard]] std::size_t size(Shelf s) const { return shelf(s).size(); }
  [[nodiscard]] std::size_t capacity(Shelf s) const { return bounds_.of(s); }
  [[nodiscard]] std::uint64_t dropped(Shelf s) const {
    return dropped_[static_cast<std::size_t>(s)];
  }
  [[nodiscard]] std::size_t memory_bytes() const { return bytes_; }
  // When this log began: a follower seeing it change knows the daemon restarted and its
  // sequence numbers began again.
  [[nodiscard]] std::int64_t started_ms() const { return started_ms_; }
  // Changes whenever what a query may return does (an entry added, pushed out, or updated by a
  // repeat): what was rendered from the log at one revision is still true at the same one.
  [[nodiscard]] std::uint64_t revision() const { return revision_; }

 private:
  static std::size_t footprint(const Event& e);
  // The entry `like` was recorded as, if its shelf still holds it.
  Event* entry(const Event& like);
  [[nodiscard]] const std::deque<Event>& shelf(Shelf s) const {
    return shelves_[static_cast<std::size_t>(s)];
  }

  HistoryBounds bounds_;
  WallClock wall_;
  std::int64_t started_ms_;
  std::array<std::deque<Event>, kShelfNames.size()> shelves_;  // each in seq order, oldest first
  std::uint64_t next_seq_ = 1;
  std::array<std::uint64_t, kShelfNames.size()> dropped_{};
  std::size_t bytes_ = 0;
  std::uint64_t revision_ = 0;
  // Each device's newest entry ("" for the gateway's own), whether or not the log still holds it.
  std::map<std::string, Event, std::less<>> newest_;
};

}  // namespace drivegate
