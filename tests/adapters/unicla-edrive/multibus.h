// A shared RS-485 line with several eDrives for the multi-drop tests: Loopback serves one driver
// and one simulator, so this small loop serves N of each. Every frame reaches every simulator;
// only the driver that sent it hears the replies. Devices take turns round-robin (priorities are
// not modelled: the tests here only poll), a silent one costs its timeout x attempts per turn.
#pragma once

#include <algorithm>
#include <vector>

#include "drivegate/driver.h"
#include "drivegate/simulator.h"

namespace drivegate::unicla::test_support {

class MultiBus {
 public:
  struct Sent {
    std::size_t device;
    TimePoint at;
    Bytes frame;
  };

  MultiBus(std::vector<Driver*> drivers, std::vector<Simulator*> sims)
      : drivers_(std::move(drivers)),
        sims_(std::move(sims)),
        last_good_(drivers_.size(), now_),
        lost_(drivers_.size(), false) {}

  void run_for(Millis span) {
    const TimePoint end = now_ + span;
    while (now_ < end) step(end);
  }

  [[nodiscard]] TimePoint now() const { return now_; }
  [[nodiscard]] bool comm_lost(std::size_t i) const { return lost_[i]; }
  std::vector<Sent> sent;
  Millis turnaround{5};

 private:
  void step(TimePoint end) {
    for (std::size_t k = 0; k < drivers_.size(); ++k) {
      const std::size_t i = (next_ + k) % drivers_.size();
      if (auto ex = drivers_[i]->next_exchange(now_)) {
        next_ = i + 1;
        transact(i, *ex);
        return;
      }
    }
    TimePoint wake = std::min(now_ + Millis(10), end);
    for (Driver* d : drivers_) wake = std::min(wake, d->wake_at());
    advance(std::max(wake, now_ + Millis(1)));
  }

  void transact(std::size_t i, const Exchange& ex) {
    Driver& d = *drivers_[i];
    for (int attempt = 0; attempt < std::max<int>(1, ex.attempts); ++attempt) {
      sent.push_back({i, now_, ex.frame});
      Bytes line;
      for (Simulator* s : sims_) {
        const Bytes r = s->on_receive(ex.frame, now_);
        line.insert(line.end(), r.begin(), r.end());
      }
      if (ex.reply == ReplyMode::none) return;
      advance(now_ + turnaround);
      bool resend = false;
      while (!line.empty()) {
        const RxVerdict v = d.on_receive(line, now_);
        if (v.kind == RxKind::incomplete) break;
        line.erase(line.begin(),
                   line.begin() + static_cast<long>(std::max<std::size_t>(1, v.consumed)));
        if (v.kind == RxKind::reply) {
          last_good_[i] = now_;
          lost_[i] = false;
          return;
        }
        if (v.kind == RxKind::bad_checksum || v.kind == RxKind::nack) resend = true;
      }
      if (!resend) advance(now_ + ex.timeout);
    }
    d.on_no_reply(now_);
  }

  void advance(TimePoint to) {
    while (now_ < to) {
      now_ = std::min(to, now_ + Millis(10));
      for (Simulator* s : sims_) s->on_tick(now_);
      for (std::size_t i = 0; i < drivers_.size(); ++i) {
        if (!lost_[i] && now_ - last_good_[i] > drivers_[i]->traits().comm_timeout) {
          lost_[i] = true;
          drivers_[i]->on_comm_lost(now_);
        }
      }
    }
  }

  std::vector<Driver*> drivers_;
  std::vector<Simulator*> sims_;
  TimePoint now_ = TimePoint{} + std::chrono::hours(1);
  std::vector<TimePoint> last_good_;
  std::vector<bool> lost_;
  std::size_t next_ = 0;
};

}  // namespace drivegate::unicla::test_support
