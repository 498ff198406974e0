// The FDC1 driver. The controller streams its status unasked every 0.5 s; the driver judges those
// bytes and publishes the state. In slave mode it sends the speed frame (72 115 ...) for the order
// it carries out: at start-up, for every write, and every refresh_s so that the controller's 60 s
// watchdog never stops the motor. Speed frames are never acknowledged: a write is in force once
// the stream shows it. The 22-byte programming frame (non-volatile memory) is offered only in
// maintenance or with allow_nv_programming, and completes by the controller's echo.
//
//   driver.cpp          the stream into points and the common state; what to send and when
//   driver_writes.cpp   check() and apply() of command and setpoint, their confirmation
//   driver_program.cpp  the programming points, prog_commit and the echo
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "points.h"
#include "program.h"
#include "settings.h"

namespace drivegate::fdc1 {

// Waiting for the programming echo: the controller writes non-volatile memory first, and the
// document gives no time (README, "Choices"). The echo alone is 22 characters on the wire.
inline constexpr Millis kEchoTimeout{2000};
static_assert(kEchoTimeout > 2 * kProgramSize * kCharacterTime);
// Programming frames go at most twice (a resend writes the identical parameters); the bus engine
// sends the second only when the device's budget_ms holds both attempts (README).
inline constexpr std::uint8_t kEchoAttempts = 2;

class Fdc1Driver final : public DriverBase {
 public:
  Fdc1Driver(const Settings& settings, bool programming);

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  // What the speed frame tells the controller: a command, and the setpoint a run runs at.
  struct Order {
    Command command = Command::stop;
    std::int32_t setpoint = 0;  // 0: none written yet
  };
  // What the stream must show for a speed write to be in force.
  enum class Expect : std::uint8_t { motor_off, motor_on, at_setpoint };
  // One write waiting for the stream: its ticket, and the speed it asked for if it was a setpoint.
  // The writes settle into completions_ (DriverBase): one order under way carries writes that
  // settle apart (a setpoint asking another speed is superseded), which a queue does not hold.
  struct Asked {
    Ticket ticket;
    std::optional<std::int32_t> rpm;
  };
  // The speed write being carried out. Every frame carries the whole order, so a write that a
  // newer one still carries out (run and run, stop and stop, the same speed) waits with it, on the
  // stricter test; one asking the opposite, or another speed, is superseded.
  struct SpeedWrite {
    std::vector<Asked> asked;
    Order order;
    Expect expect;
    TimePoint deadline;
    bool sent = false;  // a frame carrying it went out
  };
  enum class Programming : std::uint8_t { idle, queued, awaiting_echo };
  // Why a prog_commit would not go now, and the exception it gets.
  struct Blocker {
    WriteCheck verdict;
    std::string why;
  };

  // driver.cpp
  void on_status(const Status& s, TimePoint now);
  void adopt(const Status& s);
  void publish_common();
  void send_soon(TimePoint now);
  [[nodiscard]] Order on_line() const { return write_ ? write_->order : in_force_; }
  [[nodiscard]] bool slave_ready() const { return settings_.slave_mode && common_.ready; }
  // driver_writes.cpp
  [[nodiscard]] Proposed in_force() const;
  [[nodiscard]] WriteCheck judge(const WriteOp& op, const Proposed& p) const;
  WriteStatus apply_setpoint(std::int32_t rpm, Ticket t, TimePoint now);
  WriteStatus apply_command(Command c, Ticket t, TimePoint now);
  [[nodiscard]] bool shows(const Status& s, const Order& o, Expect e) const;
  WriteStatus start_write(Asked a, Order order, Expect e, TimePoint now);
  void confirm(const Status& s, TimePoint now);
  void fail_write(WriteResult r, TimePoint now);
  void expire(TimePoint now);
  // driver_program.cpp
  [[nodiscard]] WriteCheck judge_point(const WriteOp& op, const std::vector<Value>& fields) const;
  static void store_field(const WriteOp& op, std::vector<Value>& fields);
  [[nodiscard]] std::optional<Blocker> commit_blocker(const std::vector<Value>& fields) const;
  [[nodiscard]] std::optional<std::string> gather_program(const std::vector<Value>& fields,
                                                          ProgramSettings& out) const;
  WriteStatus apply_point(const WriteOp& op, Ticket t, TimePoint now);
  void finish_program(WriteResult r, ProgStatus status, std::string message);
  void publish_program();
  RxVerdict on_echo(const Echo& echo, std::size_t consumed);

  Settings settings_;
  bool programming_;

  std::optional<Status> last_status_;  // the latest streamed status since start / comm_lost
  // Slave mode. In force: what the stream confirmed, and a setpoint stored while stopped; this is
  // what common() shows. The frames carry the order of the write under way, if any, else this.
  Order in_force_;
  std::optional<SpeedWrite> write_;
  bool adopting_ = true;   // until the first status, or a write: a turning compressor is kept so
  bool send_now_ = false;  // a speed frame is due at once (start-up, a write, an undo)
  TimePoint due_at_{};     // when the frame due at once became due (wake_at)
  TimePoint next_refresh_ = TimePoint::max();

  // Programming. A failed commit's outcome stays in prog_status / prog_message until a field is
  // written again.
  Programming prog_state_ = Programming::idle;
  Program prog_sent_;
  Ticket prog_ticket_ = 0;
  std::optional<std::pair<ProgStatus, std::string>> prog_outcome_;
};

}  // namespace drivegate::fdc1
