// The stateful half of the adapter: one eDrive (one device id) on a shared RS-485 line. Reads
// Build Information and Running Limits at start-up and after every comm loss, then polls Status.
// Writes (Set Run State, Acknowledge Faults) are never acknowledged by the drive: they are sent
// with ReplyMode::none and confirmed by the status reads that follow them.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver.h"
#include "payloads.h"
#include "settings.h"

namespace drivegate::unicla {

class EDriveDriver final : public Driver {
 public:
  EDriveDriver(std::uint8_t address, Millis poll_interval, Settings settings);

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
  enum class Phase : std::uint8_t { build_information, running_limits, polling };
  enum class WriteKind : std::uint8_t { run_state, acknowledge };

  struct Awaiting {
    MessageId id;
    std::uint8_t sequence;
  };

  struct PendingWrite {
    WriteKind kind = WriteKind::run_state;
    std::vector<Ticket> tickets;       // writes this frame carries out (one, or joined ones)
    std::uint16_t speed = 0;           // run_state only
    Command previous = Command::stop;  // command in force before, restored on failure
    bool sent = false;
    TimePoint deadline{};
    bool was_running = false;  // the drive ran when the write went out
    std::int32_t rpm_at_send = 0;
    bool saw_status = false;  // a status arrived after it went out
  };

  struct SpeedLimits {
    std::uint16_t min = 0;
    std::uint16_t max = 0;
  };

  Frame request(CommandByte cmd, MessageId id, Bytes payload = {});
  Exchange send_write(PendingWrite& w, TimePoint now);
  WriteStatus queue_run_state(std::uint16_t speed, Command previous, Ticket t);
  bool control_disabled() const;
  void apply(MessageId id, const Frame& f, TimePoint now, bool& ok);
  void apply_status(const Status& s);
  void confirm(std::optional<PendingWrite>& w, const Status& s);
  void finish(std::optional<PendingWrite>& w, WriteResult r);
  void expire(TimePoint now);

  std::uint8_t address_;
  Millis poll_interval_;
  Settings settings_;
  std::vector<PointSpec> points_;
  std::vector<Value> values_;
  CommonState common_;

  Phase phase_ = Phase::build_information;
  std::uint8_t sequence_ = 0;
  std::optional<Awaiting> awaiting_;
  TimePoint next_poll_{};
  SpeedLimits build_speed_{};  // Build Information min / max, the fallback
  std::optional<SpeedLimits> limits_;
  std::optional<std::uint8_t> control_enabled_;
  std::optional<Status> status_;
  std::optional<PendingWrite> run_write_;
  std::optional<PendingWrite> ack_write_;
  std::vector<Completion> completions_;
};

}  // namespace drivegate::unicla
