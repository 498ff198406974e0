// What the bus engine keeps about each device on its line and about the line itself: health
// (last good frame, comm_lost, back-off of a silent device) and counters. A device owns its Link,
// so a device kept across a reload keeps its history; the engine updates it; the register image
// shows it. Timekeeping and counting only: no I/O.
#pragma once

#include <spdlog/logger.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>

#include "drivegate/driver.h"

namespace drivegate {

struct DeviceCounters {
  std::uint32_t frames_good = 0;
  std::uint32_t bad_checksum = 0;
  std::uint32_t timeouts = 0;
  std::uint32_t retries = 0;
  std::uint32_t nacks = 0;
  std::uint32_t foreign = 0;
  std::uint32_t noise_bytes = 0;
  // Bytes that came after this device's reply timeout, in the quiet guard time that follows it:
  // dropped, never taken as the answer to a later request (docs/safety.md, "Late replies").
  std::uint32_t late_bytes = 0;
};

// Counters of one line, shown in every one of its devices' common block.
struct BusCounters {
  std::uint32_t exchanges = 0;
  std::uint32_t timeouts = 0;
  std::uint32_t retries = 0;
  std::uint32_t echo_errors = 0;  // our own bytes did not come back as sent
  std::uint32_t noise_bytes = 0;  // bytes nobody asked for
  std::uint32_t reopens = 0;
  std::uint32_t late_bytes = 0;  // bytes in a guard time after a reply timeout, dropped
  // Not in the register map (they would wrap within hours at 115200 baud): for /metrics.
  std::uint64_t bytes_sent = 0;
  std::uint64_t bytes_received = 0;  // everything read, a one-wire line's echo included
};

// How the engine treats one device, from its configuration and its driver's traits.
struct LinkPolicy {
  Millis poll_interval{500};
  Millis budget{1000};        // most line time one turn of this device may take
  Millis backoff_max{5000};   // longest pause between probes of a silent device
  Millis comm_timeout{6000};  // no good frame for this long: comm_lost
  Micros inter_frame_gap{0};  // line silence before each of its frames
  bool streaming = false;     // sends unsolicited frames (alone on its line)
};

// Whether a device answers: comm_lost once no good frame came for the comm timeout, and a
// back-off that spaces out the probes of a device that stopped answering. Apart from that, how
// old the drive's state is: only a frame that carried it (a status, a poll's reply) makes it new;
// a write's echo proves the drive answers but says nothing about its state.
//
// A driver that reads the drive's state in parts (DriverTraits::state_in_parts: a profile's
// blocks) says when the state it publishes was last read whole: the data age counts from the
// oldest part, comm_lost comes once that is older than the comm timeout whatever else the device
// answers, and only a whole state read anew ends it.
class LinkHealth {
 public:
  explicit LinkHealth(TimePoint since, bool state_in_parts = false)
      : since_(since), last_good_(since), state_in_parts_(state_in_parts) {}

  // A good frame that carried the drive's state (RxKind::reply or frame): answers again. The
  // state it leaves in force was read whole at `state_at` (now, unless read in parts; nothing
  // while a part is still unread). True if it was comm_lost until now.
  bool data_good(TimePoint now, std::optional<TimePoint> state_at) {
    if (state_at) {
      last_data_ = *state_at;
      ever_data_ = true;
    }
    return answered(now, state_at.has_value() || !state_in_parts_);
  }
  // A good frame that carried no state (a write's echo, a refused read): answers. True if it was
  // comm_lost until now (never for a driver reading its state in parts).
  bool frame_good(TimePoint now) { return answered(now, !state_in_parts_); }
  // A turn ended without an answer: the pause before the next probe doubles from one poll
  // interval up to backoff_max, so a dead drive costs its line little while still probed.
  void turn_failed(TimePoint now, const LinkPolicy& p) {
    ++failures_;
    const int shift = std::min(failures_ - 1, 10);
    const Millis pause = std::min<Millis>(p.poll_interval * (1 << shift), p.backoff_max);
    probe_at_ = failures_ > 1 ? now + pause : TimePoint{};
  }
  // A turn ran into a reply timeout, answered in the end or not, and held the line for `held`
  // (its attempts, their timeouts and guard times): the device's next poll turn waits
  // kSickPause times that, whatever it answers meanwhile, so that waiting on a sick device takes
  // at most a third of the line from its neighbours (bus_engine.h, "Sick devices").
  void turn_held(TimePoint now, std::chrono::nanoseconds held) {
    pause_until_ = std::max(pause_until_, now + std::chrono::ceil<Millis>(held * kSickPause));
  }
  // True once: at the first call after the comm timeout passed without a good frame (or, read in
  // parts, without a whole state).
  bool lost_by(TimePoint now, Millis comm_timeout) {
    if (comm_lost_ || now <= loss_due(comm_timeout)) return false;
    comm_lost_ = true;
    return true;
  }
  // When lost_by() can next become true.
  [[nodiscard]] TimePoint loss_due(Millis comm_timeout) const {
    TimePoint basis = last_good_;
    if (state_in_parts_) basis = std::min(basis, ever_data_ ? last_data_ : since_);
    return basis + comm_timeout;
  }

  [[nodiscard]] bool comm_lost() const { return comm_lost_; }
  [[nodiscard]] bool ever_good() const { return ever_good_; }
  [[nodiscard]] TimePoint last_good() const { return last_good_; }
  // A reply came this long after its exchange's first frame was sent, too late to be taken: the
  // guard time after this device's timeouts is at least this from now on (bus_engine.h).
  void saw_late(Millis lateness) { lateness_ = std::max(lateness_, lateness); }
  [[nodiscard]] Millis lateness() const { return lateness_; }
  // When the drive's state last arrived (data_age_ms counts from it); nothing before the first.
  [[nodiscard]] std::optional<TimePoint> last_data() const {
    return ever_data_ ? std::optional<TimePoint>(last_data_) : std::nullopt;
  }
  // Whether the device waits for its next poll turn: backed off after silence, or paused after
  // a turn that held the line.
  [[nodiscard]] bool in_backoff(TimePoint now) const { return now < probe_at(); }
  [[nodiscard]] TimePoint probe_at() const { return std::max(probe_at_, pause_until_); }

  // How many times its held line time a sick device leaves to its neighbours (turn_held).
  static constexpr int kSickPause = 2;

 private:
  bool answered(TimePoint now, bool ends_loss) {
    const bool was_lost = comm_lost_;
    last_good_ = now;
    ever_good_ = true;
    if (ends_loss) comm_lost_ = false;
    failures_ = 0;
    probe_at_ = {};
    return was_lost && !comm_lost_;
  }

  TimePoint since_;
  TimePoint last_good_;
  bool state_in_parts_ = false;
  bool ever_good_ = false;
  TimePoint last_data_{};
  bool ever_data_ = false;
  Millis lateness_{0};
  bool comm_lost_ = false;
  int failures_ = 0;  // consecutive turns without an answer
  TimePoint probe_at_{};
  TimePoint pause_until_{};  // turn_held()
};

// One device's place on its line.
struct Link {
  LinkPolicy policy;
  LinkHealth health;
  DeviceCounters counters;
  const BusCounters* bus = nullptr;     // its line's, set by the engine that serves it
  std::shared_ptr<spdlog::logger> log;  // the device's own (journal fields DEVICE=, BUS=, UNIT=)
};

}  // namespace drivegate
