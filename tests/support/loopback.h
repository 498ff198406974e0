// An in-process stand-in for one bus with one device: it runs a Driver against a Simulator on
// simulated time, following the bus engine's contract (include/drivegate/driver.h), so adapter
// tests can exercise poll plans, retries, keep-alives and write confirmation without a pty and
// without waiting in real time. The daemon's own engine is tested separately, end to end.
#pragma once

#include <algorithm>
#include <functional>
#include <vector>

#include "drivegate/driver.h"
#include "drivegate/simulator.h"

namespace drivegate::test {

class Loopback {
 public:
  Loopback(Driver& driver, Simulator& sim, TimePoint start = TimePoint{} + std::chrono::hours(1))
      : driver_(driver), sim_(sim), now_(start), last_good_(start) {}

  // Time the simulated device takes to start answering.
  Millis turnaround{5};
  // When set, bytes from the device pass through this first (to corrupt or drop them).
  std::function<Bytes(Bytes)> line_filter;

  // Runs the bus until `span` of simulated time has passed.
  void run_for(Millis span) {
    const TimePoint end = now_ + span;
    while (now_ < end) step(end);
  }

  // Runs until `done()` holds or `limit` passes; returns whether it held.
  bool run_until(const std::function<bool()>& done, Millis limit) {
    const TimePoint end = now_ + limit;
    while (!done()) {
      if (now_ >= end) return false;
      step(end);
    }
    return true;
  }

  [[nodiscard]] TimePoint now() const { return now_; }
  [[nodiscard]] bool comm_lost() const { return comm_lost_; }
  // Every frame the driver put on the wire, resends included, in order.
  std::vector<Bytes> sent;
  std::vector<Completion> completions;
  int timeouts = 0;
  int retries = 0;
  int good_frames = 0;
  int bad_frames = 0;
  int nacks = 0;

 private:
  void step(TimePoint end) {
    if (auto ex = driver_.next_exchange(now_)) {
      transact(*ex);
    } else {
      const TimePoint wake = std::min({driver_.wake_at(), now_ + Millis(10), end});
      advance(std::max(wake, now_ + Millis(1)));
    }
    collect();
  }

  void transact(const Exchange& ex) {
    for (int attempt = 0; attempt < std::max<int>(1, ex.attempts); ++attempt) {
      if (attempt > 0) ++retries;
      sent.push_back(ex.frame);
      Bytes reply = sim_.on_receive(ex.frame, now_);
      if (ex.reply == ReplyMode::none) return;
      advance(now_ + turnaround);
      if (line_filter) reply = line_filter(std::move(reply));
      switch (deliver(reply)) {
        case Outcome::reply:
          return;
        case Outcome::resend:
          continue;
        case Outcome::silence:
          ++timeouts;
          advance(now_ + ex.timeout);
          continue;
      }
    }
    driver_.on_no_reply(now_);
  }

  enum class Outcome { reply, resend, silence };

  Outcome deliver(Bytes rx) {
    pending_.insert(pending_.end(), rx.begin(), rx.end());
    Outcome outcome = Outcome::silence;
    while (!pending_.empty()) {
      const RxVerdict v = driver_.on_receive(pending_, now_);
      if (v.kind == RxKind::incomplete) break;
      pending_.erase(pending_.begin(),
                     pending_.begin() + static_cast<long>(std::max<std::size_t>(1, v.consumed)));
      switch (v.kind) {
        case RxKind::reply:
          good();
          pending_.clear();
          return Outcome::reply;
        case RxKind::frame:
          good();
          break;
        case RxKind::nack:
          ++nacks;
          outcome = Outcome::resend;
          break;
        case RxKind::bad_checksum:
          ++bad_frames;
          outcome = Outcome::resend;
          break;
        default:
          break;
      }
    }
    if (outcome == Outcome::resend) pending_.clear();
    return outcome;
  }

  void good() {
    ++good_frames;
    last_good_ = now_;
    comm_lost_ = false;
  }

  void advance(TimePoint to) {
    while (now_ < to) {
      now_ = std::min(to, now_ + Millis(10));
      Bytes unsolicited = sim_.on_tick(now_);
      if (!unsolicited.empty()) {
        if (line_filter) unsolicited = line_filter(std::move(unsolicited));
        deliver(std::move(unsolicited));
      }
      if (!comm_lost_ && now_ - last_good_ > driver_.traits().comm_timeout) {
        comm_lost_ = true;
        driver_.on_comm_lost(now_);
      }
    }
  }

  void collect() { driver_.take_completions(completions); }

  Driver& driver_;
  Simulator& sim_;
  TimePoint now_;
  TimePoint last_good_;
  bool comm_lost_ = false;
  Bytes pending_;
};

}  // namespace drivegate::test
