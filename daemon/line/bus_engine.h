// The bus engine: one serial line, the devices on it, one transaction at a time. It keeps the
// contract of include/drivegate/driver.h with every driver (through the devices, line/station.h)
// and owns everything about time on the line: the inter-frame gap, reply timeouts counting the
// frame's own time on the wire, identical resends on timeout, bad checksum or NACK, one-wire echo
// suppression that checks the echo equals what was sent, unsolicited frames for a streaming
// device, writes before polls, round-robin among equals, each device's time budget, back-off of
// silent devices, comm_lost, and the counters.
//
// Time and the line are injected: the daemon wires BusClock and BusLine to Asio (line/bus.h), the
// tests to a simulated clock and line (tests/support/sim_line.h), and both run this same code.
// Nothing here blocks or sleeps; every event is a call in, every action a call out.
#pragma once

#include <spdlog/logger.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "config/config.h"
#include "line/frame_tap.h"
#include "line/link.h"
#include "line/station.h"

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

  // Every frame sent and received goes to `tap` too, until remove_tap() (line/frame_tap.h).
  void add_tap(FrameTap* tap);
  void remove_tap(FrameTap* tap);

  [[nodiscard]] const BusCounters& counters() const { return counters_; }
  [[nodiscard]] bool line_is_up() const { return state_ != State::down; }
  [[nodiscard]] const std::vector<Station*>& stations() const { return stations_; }

 private:
  enum class State : std::uint8_t { down, idle, gap, sending, awaiting_echo, awaiting_reply };

  void tick(TimePoint now);
  void pump(TimePoint now);
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
  TimePoint last_activity_{};
  BusCounters counters_;
  std::vector<FrameTap*> taps_;  // captures in progress; usually none
};

}  // namespace drivegate
