// The Nidec washer driver: ping handshake, poll plan, command translation and fault mapping.
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver.h"
#include "points.h"

namespace drivegate::nidec {

struct DriverConfig {
  std::uint8_t platform = 7;           // 5.1 ping byte 3
  std::uint16_t empty_raw_weight = 0;  // 5.1 ping bytes 4..5
  std::uint16_t accel_100ms = 30;      // 5.3: accel time in 100 ms units
  std::uint8_t attempts = 3;           // identical sends per turn (section 6: resend)
  Millis poll_interval{500};           // section 6: 500 ms recommended, 1 s at most
  Millis confirm_timeout{2500};        // a queued write not confirmed by then fails
};

// Reads the validated [device.options] (see plugin.cpp) and the poll interval.
DriverConfig config_from(const DeviceEnv& env);

class WasherDriver final : public Driver {
 public:
  explicit WasherDriver(const DriverConfig& config);

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
  // What a queued frame is for: decides how its ACK completes the write.
  enum class Job : std::uint8_t { run, stop, reset_fault, action };
  struct Queued {
    Request request;
    Job job;
    Ticket ticket;
    TimePoint deadline;
    Command command = Command::stop;   // run / stop: the command in force once ACKed
    Motion motion = Motion::rotation;  // run: the motion in force once ACKed
  };
  enum class InFlight : std::uint8_t { none, ping, poll, queued };

  Exchange exchange(const Request& r, Priority p) const;
  std::optional<Request> run_request(Command c, Motion m) const;
  WriteStatus enqueue(Queued q);
  void expire(TimePoint now);
  void finish(const Queued& q, WriteResult result);
  void complete_front(const Reply& r);
  void apply(const Reply& r);
  void apply_error(std::uint8_t error);
  void apply_speed(std::uint16_t rpm);
  void set_command(Command c);
  void update_running();
  WriteStatus write_action(std::int64_t n, Ticket t, TimePoint now);

  DriverConfig config_;
  std::vector<PointSpec> points_;
  std::vector<Value> values_;
  CommonState common_;

  bool ready_ = false;                  // ping answered since start / comm_lost
  std::optional<TimePoint> next_poll_;  // empty: at once
  TimePoint last_sent_{};
  InFlight in_flight_ = InFlight::none;
  Mode expected_ = Mode::request;
  std::deque<Queued> queue_;
  std::vector<Completion> completions_;

  Motion motion_ = Motion::rotation;
  Motion motion_in_force_ = Motion::rotation;
  std::uint16_t setpoint_ = 0;
  std::uint16_t accel_100ms_;
  AgitationTiming agitation_;
  bool forced_brake_ = false;
};

}  // namespace drivegate::nidec
