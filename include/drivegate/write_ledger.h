// The bookkeeping of a driver's writes on their way to the drive, one helper for every driver.
//
// `Completions`: the outcomes of writes settled since the gateway last asked, which
// Driver::take_completions() hands over (DriverBase, driver_base.h, keeps one and does that).
//
// `WriteLedger<Job>`: every part apply() answered `pending`, in the order applied, each with the
// tickets it carries out (a later write the same frame carries out too joins it), its deadline and
// whether a frame of it went out, beside what the driver itself keeps of it (`Job`). Settling an
// entry removes it and gives its tickets their outcome in the `Completions` it was made with (its
// own when none is given). A driver that moves the write on the line out of the queue (a request
// built from it) takes it with take_front() and settles it later with settle(). Header-only, no
// clock: time is the `now` given.
//
//   struct Job { Change change; std::uint16_t rpm; };
//   WriteLedger<Job> writes_{completions_};
//   WriteStatus apply(...)  { writes_.push({Change::run, rpm}, ticket, now + kConfirm); ... }
//   next_exchange(now)      { writes_.expire(now); if (auto* w = writes_.first_unsent()) ... }
//   on_receive(...)         { if (took) writes_.settle_front(WriteResult::ok); }
//   on_comm_lost(now)       { writes_.settle_all(WriteResult::no_response); }
#pragma once

#include <algorithm>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include "drivegate/bytes.h"
#include "drivegate/driver.h"

namespace drivegate {

// Outcomes of writes settled since the gateway last asked, in the order they settled.
class Completions {
 public:
  void add(Ticket t, WriteResult r, Bytes reply = {}) { list_.push_back({t, r, std::move(reply)}); }
  // Driver::take_completions(): appended to `out`, and handed over once.
  void take(std::vector<Completion>& out) {
    for (Completion& c : list_) out.push_back(std::move(c));
    list_.clear();
  }
  [[nodiscard]] bool empty() const { return list_.empty(); }

 private:
  std::vector<Completion> list_;
};

template <class Job>
class WriteLedger {
 public:
  struct Entry {
    Job job;
    std::vector<Ticket> tickets;  // none: the driver's own frame (an undo), settled silently
    TimePoint deadline{};  // settled no_response by expire() at it, by expire_after() past it
    bool sent = false;     // a frame carrying it went out
  };
  // Told of every entry as it settles, after it left the queue: the driver's own consequences (a
  // status point, undoing on the drive a write that failed). It must not touch this queue; what it
  // decides to send next it keeps aside.
  using Settled = std::function<void(const Entry&, WriteResult)>;

  WriteLedger() = default;
  explicit WriteLedger(Settled on_settled) : on_settled_(std::move(on_settled)) {}
  // Outcomes go to `done` (the driver's, which take_completions() hands over).
  explicit WriteLedger(Completions& done, Settled on_settled = {})
      : done_(&done), on_settled_(std::move(on_settled)) {}
  // `done_` may point at `own_`: neither copied nor moved.
  WriteLedger(const WriteLedger&) = delete;
  WriteLedger& operator=(const WriteLedger&) = delete;

  [[nodiscard]] bool empty() const { return entries_.empty(); }
  [[nodiscard]] std::size_t size() const { return entries_.size(); }
  Entry& front() { return entries_.front(); }
  [[nodiscard]] const Entry& front() const { return entries_.front(); }
  Entry& back() { return entries_.back(); }
  auto begin() { return entries_.begin(); }
  auto end() { return entries_.end(); }
  [[nodiscard]] auto begin() const { return entries_.begin(); }
  [[nodiscard]] auto end() const { return entries_.end(); }

  // A write applied: at the back, or at the front (an undo goes before what waits).
  Entry& push(Job job, Ticket t, TimePoint deadline) {
    entries_.push_back({std::move(job), {t}, deadline, false});
    return entries_.back();
  }
  Entry& push_front(Job job, std::vector<Ticket> tickets, TimePoint deadline) {
    entries_.push_front({std::move(job), std::move(tickets), deadline, false});
    return entries_.front();
  }
  // The front entry, out of the queue but not settled: the driver holds it while its frame is on
  // the line, and settles it with settle(). The queue must not be empty.
  Entry take_front() {
    Entry e = std::move(entries_.front());
    entries_.pop_front();
    return e;
  }
  // An entry taken out of the queue (take_front()), or kept apart by the driver, settles: its
  // tickets get `r`, and `reply` where the write is a forwarded request (Completion::reply).
  void settle(const Entry& e, WriteResult r, Bytes reply = {}) { finish(e, r, std::move(reply)); }

  // A later write that `e`'s frame carries out as well: it settles with `e`.
  void join(Entry& e, Ticket t) { e.tickets.push_back(t); }

  // The first entry no frame of which went out yet (only the front is ever on the line).
  Entry* first_unsent() {
    const auto it =
        std::find_if(entries_.begin(), entries_.end(), [](const Entry& e) { return !e.sent; });
    return it == entries_.end() ? nullptr : &*it;
  }
  [[nodiscard]] bool front_on_line() const { return !entries_.empty() && entries_.front().sent; }

  // Settling, each entry removed and its tickets given `r`.
  void settle_front(WriteResult r) {
    if (entries_.empty()) return;
    Entry e = std::move(entries_.front());
    entries_.pop_front();
    finish(e, r);
  }
  // Every entry `pred` holds for, in order; how many.
  template <class Pred>
  std::size_t settle_if(Pred pred, WriteResult r) {
    const std::vector<Entry> out = take_if(pred);
    for (const Entry& e : out) finish(e, r);
    return out.size();
  }
  // Every entry `pred` holds for, in order, out of the queue but not settled: a write another one
  // carries out (its tickets joined to that one's, join()), or the driver settles later.
  template <class Pred>
  std::vector<Entry> take_if(Pred pred) {
    std::vector<Entry> out;
    for (auto it = entries_.begin(); it != entries_.end();) {
      if (pred(static_cast<const Entry&>(*it))) {
        out.push_back(std::move(*it));
        it = entries_.erase(it);
      } else {
        ++it;
      }
    }
    return out;
  }
  // Superseded: the entries still waiting for the line (a later write decides what it carries).
  std::size_t settle_unsent(WriteResult r = WriteResult::no_response) {
    return settle_if([](const Entry& e) { return !e.sent; }, r);
  }
  // comm_lost, shutdown: everything.
  std::size_t settle_all(WriteResult r = WriteResult::no_response) {
    return settle_if([](const Entry&) { return true; }, r);
  }
  // Entries whose deadline has come: no_response ("did not take it in time").
  std::size_t expire(TimePoint now) {
    return settle_if([now](const Entry& e) { return e.deadline <= now; }, WriteResult::no_response);
  }
  // Entries whose deadline has passed, where the deadline is the last moment a write may still
  // go out (a send-by): no_response, and never sent.
  std::size_t expire_after(TimePoint now) {
    return settle_if([now](const Entry& e) { return e.deadline < now; }, WriteResult::no_response);
  }
  // The earliest deadline, for wake_at().
  [[nodiscard]] std::optional<TimePoint> next_deadline() const {
    std::optional<TimePoint> t;
    for (const Entry& e : entries_) {
      if (!t || e.deadline < *t) t = e.deadline;
    }
    return t;
  }

  // A part that settles without an entry of its own (a write refused after the fact).
  void complete(Ticket t, WriteResult r) { done_->add(t, r); }
  void take_completions(std::vector<Completion>& out) { done_->take(out); }
  [[nodiscard]] bool has_completions() const { return !done_->empty(); }

 private:
  void finish(const Entry& e, WriteResult r, Bytes reply = {}) {
    for (const Ticket t : e.tickets) done_->add(t, r, reply);
    if (on_settled_) on_settled_(e, r);
  }

  std::deque<Entry> entries_;
  Completions own_;
  Completions* done_ = &own_;
  Settled on_settled_;
};

// How many of `attempts` identical sends fit before `deadline`, each taking `per_attempt` at most
// (its frame, the reply timeout and the guard after it, the gap): only those that start before
// the deadline, and always one, so that no reply can put a write in force after the gateway was
// told it failed.
inline std::uint8_t attempts_before(TimePoint deadline, TimePoint now, Millis per_attempt,
                                    std::uint8_t attempts) {
  if (per_attempt.count() <= 0) return attempts;
  const auto left = std::chrono::duration_cast<Millis>(deadline - now);
  const auto fit = (left + per_attempt - Millis(1)) / per_attempt;
  return static_cast<std::uint8_t>(std::clamp<std::int64_t>(fit, 1, std::int64_t{attempts}));
}

}  // namespace drivegate
