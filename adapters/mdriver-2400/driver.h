// The stateful mdriver-2400 driver: fixed-code check until answered, then the run command as poll
// and keep-alive, writes confirmed by the target code the run reply echoes.
#pragma once

#include <optional>
#include <vector>

#include "codec.h"
#include "config.h"
#include "drivegate/driver.h"

namespace drivegate::mdriver {

// Indices into points() / values().
enum class Pt : std::size_t {
  target_code,
  target_rpm,
  actual_code,
  error_code,
  ipm_temperature,
  info_1,
  info_2,
  info_3,
  sent_code,
  fixed_code_state,
  count,
};
std::vector<PointSpec> make_points();

// Values of the fixed_code_state point.
enum class FixedCodeState : std::uint8_t { unchecked = 0, ok = 1, error = 2 };

// Section 3 No.2: codes up to 0x0E stop; the driver stops with 0x01 (0x00 would also reset a
// latched error).
inline constexpr std::uint8_t kStopCode = 0x01;
// The driver fails a write its reply has not confirmed after this (under the gateway's 3 s).
inline constexpr Millis kConfirmDeadline{2500};
// 2400 baud: a 13-byte reply takes 54 ms on the wire; the document gives no answer time.
inline constexpr Millis kReplyTimeout{200};
inline constexpr std::uint8_t kAttempts = 3;

class MDriver final : public Driver {
 public:
  MDriver(const Config& config, Millis poll_interval);

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
  enum class Phase : std::uint8_t { check, ready, fixed_code_error };
  enum class Awaiting : std::uint8_t { nothing, check, run };
  struct Pending {
    Ticket ticket;
    std::uint8_t code;  // the D4 that confirms it when echoed in R4
    TimePoint deadline;
    bool in_flight;
  };

  [[nodiscard]] std::uint8_t target_code() const;
  [[nodiscard]] bool device_error() const;
  [[nodiscard]] bool has_unsent() const;
  Exchange make_exchange(Wire frame, Priority p) const;
  RxKind on_check_reply(const Frame& f, TimePoint now);
  RxKind on_run_reply(const Frame& f);
  WriteStatus queue(Ticket t, std::uint8_t code, TimePoint now);
  void finish_in_flight(WriteResult r);
  void fail_all();
  void expire(TimePoint now);
  void refresh();

  Config cfg_;
  Millis cadence_;
  Phase phase_ = Phase::check;
  Awaiting awaiting_ = Awaiting::nothing;
  TimePoint next_due_{};  // epoch: at once
  Command command_ = Command::stop;
  std::optional<std::uint8_t> setpoint_code_;
  bool reset_requested_ = false;
  std::optional<RunReply> last_;
  std::optional<std::uint8_t> sent_code_;
  std::vector<Pending> pending_;
  std::vector<Completion> done_;
  std::vector<PointSpec> points_;
  std::vector<Value> values_;
  CommonState common_;
};

}  // namespace drivegate::mdriver
