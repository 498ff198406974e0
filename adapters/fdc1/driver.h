// The FDC1 driver. The controller streams its status unasked every 0.5 s; the driver judges
// those bytes, publishes the state, and in slave mode sends the speed frame (72 115 ...) for the
// command in force: at start-up, on every write, and every refresh_s so that the controller's
// 60 s watchdog never stops the motor. Speed frames are never acknowledged: a write completes
// when the stream shows it. The 22-byte programming frame (non-volatile memory) is offered only
// in maintenance or with allow_nv_programming, and completes by the controller's echo.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "codec.h"
#include "drivegate/driver.h"
#include "points.h"
#include "program.h"
#include "settings.h"

namespace drivegate::fdc1 {

// Waiting for the programming echo: the controller writes non-volatile memory first, and the
// document gives no time. drivegate's choice; the echo alone is 183 ms at 1200 baud.
inline constexpr Millis kEchoTimeout{2000};
// Programming frames are sent at most twice (a resend writes the identical parameters).
inline constexpr std::uint8_t kEchoAttempts = 2;

class Fdc1Driver final : public Driver {
 public:
  Fdc1Driver(const Settings& settings, bool programming);

  [[nodiscard]] DriverTraits traits() const override;
  [[nodiscard]] const std::vector<PointSpec>& points() const override { return points_; }
  [[nodiscard]] const std::vector<Value>& values() const override { return values_; }
  [[nodiscard]] const CommonState& common() const override { return common_; }

  std::optional<Exchange> next_exchange(TimePoint now) override;
  [[nodiscard]] TimePoint wake_at() const override;
  RxVerdict on_receive(ByteView rx, TimePoint now) override;
  void on_no_reply(TimePoint now) override;
  void on_comm_lost(TimePoint now) override;

  WriteStatus command(Command c, Ticket t, TimePoint now) override;
  WriteStatus setpoint(std::int32_t rpm, Ticket t, TimePoint now) override;
  WriteStatus write(std::size_t point, const Value& v, Ticket t, TimePoint now) override;
  void take_completions(std::vector<Completion>& out) override;

 private:
  // What the stream must show for a pending speed write to complete ok.
  enum class Expect : std::uint8_t { motor_on, motor_off, at_setpoint };
  // One frame's worth of pending writes: a write that a newer frame still carries out (a
  // setpoint and a run_forward in one Modbus request, say) waits with it, not against it.
  // The command and setpoint in force.
  struct InForce {
    Command command;
    std::int32_t setpoint;
  };
  struct SpeedWrite {
    std::vector<Ticket> tickets;
    Expect expect;
    TimePoint deadline;
    InForce before;     // in force before the first of these writes
    bool sent = false;  // a frame carrying them went out
  };
  enum class Programming : std::uint8_t { idle, queued, awaiting_echo };

  void apply(const Status& s, TimePoint now);
  void confirm(const Status& s);
  void expire(TimePoint now);
  void start_speed_write(Ticket t, Expect e, InForce before, TimePoint now);
  void complete(Ticket t, WriteResult r);
  void finish_speed_write(WriteResult r);
  void give_up_speed_write();
  [[nodiscard]] InForce in_force() const { return {common_.command, setpoint_}; }
  [[nodiscard]] Speed wanted_speed() const;
  [[nodiscard]] bool slave_ready() const { return settings_.slave_mode && common_.ready; }

  WriteStatus commit_program(Ticket t, TimePoint now);
  std::optional<std::string> gather_program(ProgramSettings& out) const;
  void finish_program(WriteResult r, ProgStatus status, std::string message);
  RxVerdict on_echo(const Echo& echo);

  Settings settings_;
  bool programming_;
  std::vector<PointSpec> points_;
  std::vector<Value> values_;
  CommonState common_;

  bool motor_on_ = false;
  std::int32_t setpoint_ = 0;  // 0: none written yet
  bool send_now_ = false;      // a speed frame is due at once (start-up or a write)
  Priority send_priority_ = Priority::poll;
  TimePoint due_at_{};  // when the frame due at once became due (wake_at)
  TimePoint next_refresh_ = TimePoint::max();
  std::optional<SpeedWrite> speed_write_;

  Programming prog_state_ = Programming::idle;
  Program prog_sent_;
  Ticket prog_ticket_ = 0;

  std::vector<Completion> completions_;
};

std::unique_ptr<Driver> make_driver(const DeviceEnv& env, std::string& error);

}  // namespace drivegate::fdc1
