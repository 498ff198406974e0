// The Nidec washer driver: ping handshake and poll plan (driver.cpp), what each ACK tells
// (driver_replies.cpp), and Modbus writes judged, queued and confirmed (driver_writes.cpp).
#pragma once

#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "points.h"
#include "settings.h"

namespace drivegate::nidec {

class NidecWasherDriver final : public DriverBase {
 public:
  // `poll_interval` is the device's; section 6 wants a frame every second at least.
  NidecWasherDriver(const Settings& settings, Millis poll_interval);

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  // What a queued write is for: decides how its frame is made and how its ACK completes it.
  enum class Job : std::uint8_t { run, setpoint, stop, reset_fault, action };
  // Its ticket and deadline are the ledger's.
  struct Queued {
    Job job = Job::action;
    Command command = Command::stop;   // run / stop: the command in force once ACKed
    Motion motion = Motion::rotation;  // run: the motion in force once ACKed
    std::uint16_t rpm = 0;             // setpoint: the setpoint in force once ACKed
    // The frame. Run and setpoint frames are made when they first reach the line, from what is
    // in force then (driver_writes.cpp); every other frame when the write is applied.
    std::optional<Request> request;
  };
  using Writes = WriteLedger<Queued>;
  enum class InFlight : std::uint8_t { none, ping, poll, queued };

  // The state a write is judged against: as it is now (judged_now()), or as the parts of a
  // request before it would leave it (check()).
  struct Judged {
    Motion motion = Motion::rotation;  // what a run starts (the `motion` point)
    bool faulted = false;              // the last ACK carried Error bits (section 8)
    bool forced_brake = false;         // 5.13
  };

  // driver.cpp
  [[nodiscard]] Exchange exchange(const Request& r) const;
  void set_command(Command c);
  void update_running();

  // driver_replies.cpp
  void apply_reply(const Reply& r);
  void apply_error(std::uint8_t error);
  void apply_speed(std::uint16_t rpm);

  // driver_writes.cpp
  [[nodiscard]] Judged judged_now() const;
  [[nodiscard]] static WriteCheck judge(const WriteOp& op, Judged& state);
  [[nodiscard]] std::optional<Request> run_request(Command c, Motion m, std::uint16_t rpm) const;
  WriteStatus apply_command(Command c, Ticket t, TimePoint deadline);
  WriteStatus apply_setpoint(std::uint16_t rpm, Ticket t, TimePoint deadline);
  WriteStatus apply_point(std::size_t point, const Value& v, Ticket t, TimePoint deadline);
  WriteStatus apply_action(Action a, Ticket t, TimePoint deadline);
  WriteStatus enqueue(Queued q, Ticket t, TimePoint deadline);
  void supersede_motion();
  [[nodiscard]] bool motion_queued() const;
  const Writes::Entry* front_to_send();
  void complete_front(const Reply& r);
  void settled(const Queued& q, WriteResult result);

  Settings settings_;
  Millis poll_interval_;

  // Line
  std::optional<TimePoint> next_poll_;  // empty: at once
  TimePoint last_sent_{};
  InFlight in_flight_ = InFlight::none;
  Mode expected_ = Mode::request;
  Writes queue_{completions_, [this](const Writes::Entry& e, WriteResult r) { settled(e.job, r); }};

  // Settings of the next run, written through points: the gateway's, not the drive's.
  Motion motion_ = Motion::rotation;
  std::uint16_t accel_100ms_;
  AgitationTiming agitation_;

  // In force at the drive, as its ACKs showed.
  Motion motion_in_force_ = Motion::rotation;
  bool forced_brake_ = false;
};

}  // namespace drivegate::nidec
