// The bus engine: one serial line, the devices on it, one transaction at a time. It keeps the
// contract of include/drivegate/driver.h with every driver (through the devices, bus/station.h)
// and owns everything about time on the line: the inter-frame gap, reply timeouts counting the
// frame's own time on the wire, identical resends on timeout, bad checksum or NACK, one-wire echo
// suppression that checks the echo equals what was sent, unsolicited frames for a streaming
// device, each device's time budget, back-off of silent devices, comm_lost, and the counters.
//
// Fair line time. Urgent writes (a stop) go first. Otherwise, when writes and polls both wait,
// a write turn and a poll turn alternate, each round-robin among the devices, so a write storm
// to one device takes at most every other exchange and every device on the line, the written
// one included, keeps being polled (docs/safety.md, "Fair line time").
//
// Late replies. After a reply timeout the line is kept quiet for a guard time (the exchange's
// reply timeout again, guard_time()) before the resend or the next exchange. Bytes that arrive
// in it are a late reply: dropped and counted as late_bytes. The device is then known to answer
// late: the exchange gets no more attempts (a reply in the next attempt's window could be the
// late one), the quiet lasts until the replies to all its attempts can have come (the guard
// again from the late bytes, plus the time between its first and last attempt), and from then
// on the device's guard is at least the lateness seen (at most kMaxGuard). An exchange answered
// only after a timeout, by a device known to answer late, is followed by such a quiet too. So a
// reply is never taken for the answer to another request, and a drive that always answers late
// goes comm_lost.
//
// Sick devices. A device whose turn runs into a reply timeout, silent, late or answering every
// other request, held the line for the turn's attempts, timeouts and guard times: its next poll
// turn waits twice that (LinkHealth::turn_held), answered meanwhile or not, on top of the back-off
// of a device that stopped answering. Waiting on it then takes at most a third of the line, and
// every healthy device beside it keeps at least half its poll rate; the sick device pays with
// its own. Writes are not held back: they take their write turns as before. A device alone on
// its line pays nothing: there is nobody to leave the time to.
//
// Time and the line are injected: the daemon wires BusClock and BusLine to Asio (bus/bus.h), the
// tests to a simulated clock and line (tests/support/sim_line.h), and both run this same code.
// Nothing here blocks or sleeps; every event is a call in, every action a call out.
#pragma once

#include <spdlog/logger.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "bus/frame_tap.h"
#include "bus/link.h"
#include "bus/station.h"
#include "config/config.h"

namespace drivegate {

// The engine's view of time: what time it is, and one alarm.
class BusClock {
 public:
  virtual ~BusClock() = default;
  [[nodiscard]] virtual TimePoint now() const = 0;
  // BusEngine::on_alarm() is to be called at `at` (at once if it is past), never from inside
  // this call. Replaces the alarm set before.
  virtual void set_alarm(TimePoint at) = 0;
};

// The engine's view of the line: bytes out. Bytes in, and the line opening and failing, come back
// as calls to the engine (on_received, line_up, line_down).
class BusLine {
 public:
  virtual ~BusLine() = default;
  // Starts writing `frame`; BusEngine::on_sent() follows once the kernel has it (or line_down()
  // when the write failed), never from inside this call.
  virtual void send(ByteView frame) = 0;
};

// How often every device's deadlines are looked at, line up or down (comm_lost, write deadlines,
// the PLC-loss failsafe).
inline constexpr Millis kTickPeriod{100};

class BusEngine {
 public:
  BusEngine(const BusConfig& config, std::vector<Station*> stations, BusClock& clock, BusLine& line,
            std::shared_ptr<spdlog::logger> log);
  ~BusEngine();
  BusEngine(const BusEngine&) = delete;
  BusEngine& operator=(const BusEngine&) = delete;

  // Ticks begin and the devices may ask for the line; nothing is sent before line_up().
  void start();
  // Nothing more is sent or acted on; the exchange in flight is dropped.
  void stop();
  // The line is open (again, when `reopened`).
  void line_up(bool reopened);
  // The line failed: the exchange in flight fails as unanswered; nothing is sent until line_up().
  void line_down();
  // The last send() has been written.
  void on_sent();
  // Bytes from the line, in whatever chunks they came.
  void on_received(ByteView bytes);
  // The alarm set through BusClock came due (or not quite: every deadline is checked against now).
  void on_alarm();
  // Something new may be due (a write was queued): look as soon as the line is free.
  void kick();

  // The devices on the line change (a reload): those that stay keep everything, those that go
  // are forgotten (an exchange of theirs in flight is abandoned, the line kept quiet for its
  // reply timeout), new ones are polled from the next turn.
  void replace_stations(std::vector<Station*> stations);

  // Every frame sent and received goes to `tap` too, until remove_tap() (bus/frame_tap.h).
  void add_tap(FrameTap* tap);
  void remove_tap(FrameTap* tap);

  [[nodiscard]] const BusCounters& counters() const { return counters_; }
  [[nodiscard]] bool line_is_up() const { return state_ != State::down; }
  [[nodiscard]] const std::vector<Station*>& stations() const { return stations_; }

 private:
  enum class State : std::uint8_t { down, idle, gap, sending, awaiting_echo, awaiting_reply };
  enum class Pick : std::uint8_t { urgent, write, poll };

  void tick(TimePoint now);
  void pump(TimePoint now);
  bool take_turn(Pick pick, TimePoint now);
  void begin(Station& st, Exchange ex, TimePoint now);
  void send_attempt(TimePoint now);
  void after_sent(TimePoint now);
  void advance(TimePoint now);
  void process_rx(Station& st, TimePoint now);
  void on_deadline(TimePoint now);
  void attempt_failed(TimePoint now);
  void finish(TimePoint now);
  void rearm(TimePoint now);
  [[nodiscard]] TimePoint idle_wake(TimePoint now) const;
  // The line was busy until `t` (bytes in, or ours leaving): the inter-frame gap counts from it.
  void note_activity(TimePoint t) { last_activity_ = std::max(last_activity_, t); }
  // The next frame may go once the gap after the last activity and any guard time have passed.
  [[nodiscard]] TimePoint clear_at(Micros gap) const {
    return std::max(last_activity_ + gap, quiet_until_);
  }
  void start_guard(Station& owner, TimePoint now);
  void give_up(TimePoint now);
  // The exchange in flight is over: the line is idle again. Returns its station.
  Station* release();
  // It ended without its reply: the station hears so and, `silent`, is backed off.
  void unanswered(TimePoint now, bool silent);
  // The exchange ran into a timeout: its device pauses for the line time it held.
  void note_held(Station& st, TimePoint now);
  [[nodiscard]] static Millis guard_for(const Link& link, Millis wait);
  void late_bytes(ByteView bytes, TimePoint now);
  void tap(FrameDirection dir, std::uint8_t flags, const Station* st, ByteView bytes,
           TimePoint now) const {
    if (taps_.empty() || bytes.empty()) return;
    const TappedFrame f{dir, flags, st, bytes};
    for (FrameTap* t : taps_) t->on_frame(f, now);
  }
  [[nodiscard]] std::chrono::nanoseconds on_wire(std::size_t bytes) const {
    return char_time_ * static_cast<long>(bytes);
  }

  std::string name_;
  bool echo_line_;
  Millis network_delay_;  // added to every reply (and echo) timeout
  std::chrono::nanoseconds char_time_;
  std::vector<Station*> stations_;
  BusClock& clock_;
  BusLine& line_;
  std::shared_ptr<spdlog::logger> log_;
  Station* streaming_ = nullptr;  // the device unsolicited bytes belong to, if any

  bool started_ = false;
  bool kicked_ = false;
  State state_ = State::down;
  TimePoint deadline_{};  // of the gap or the wait the state is in
  TimePoint next_tick_{};
  Bytes rx_;
  Bytes echo_;  // bytes still expected back on a one-wire line
  bool echo_broken_ = false;
  Station* current_ = nullptr;
  std::optional<Exchange> exchange_;
  int attempt_ = 0;
  int max_attempts_ = 1;
  bool answered_ = false;         // the device sent something this exchange, if only a NACK
  std::size_t next_station_ = 0;  // round-robin position
  bool last_turn_was_write_ = false;
  TimePoint last_activity_{};
  // The guard time after a reply timeout: nothing is sent before quiet_until_, and bytes before
  // it are guard_owner_'s late reply. The guard is extended by late bytes up to guard_limit_.
  TimePoint quiet_until_{};
  TimePoint guard_started_{};
  std::chrono::nanoseconds guard_{0};
  Station* guard_owner_ = nullptr;
  TimePoint guard_last_sent_{};               // the guarded exchange's last frame went then
  std::chrono::nanoseconds guard_spread_{0};  // from its first frame to its last
  TimePoint first_sent_{};                    // when the exchange in progress sent its first frame
  TimePoint last_sent_{};                     // and its latest
  bool timed_out_ = false;                    // an attempt of the exchange in progress timed out
  BusCounters counters_;
  std::vector<FrameTap*> taps_;  // captures in progress; usually none
};

}  // namespace drivegate
