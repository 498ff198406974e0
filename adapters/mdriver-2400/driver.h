// The stateful mdriver-2400 driver: the fixed-code check until it is answered, then the run
// command as poll and keep-alive, carrying the target code in force; a write is in force once the
// run reply echoed the code that carries it.
//
//   driver.cpp         the poll plan, replies into points and the common state
//   driver_writes.cpp  check() and apply(), the writes waiting for the line, their confirmation
#pragma once

#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "settings.h"

namespace drivegate::mdriver {

// Section 3 No.2: codes up to 0x0E stop; the driver stops with 0x01 (0x00 would also reset a
// latched error, so it is kept for reset_fault).
inline constexpr std::uint8_t kStopCode = 0x01;
// The driver fails a write the drive has not confirmed after this, under the gateway's 3 s
// (traits().write_timeout), so that the PLC gets the driver's own answer.
inline constexpr Millis kConfirmDeadline{2500};
// Not in the document, which gives no answer time: a 13-byte run reply takes 54 ms on the wire
// (section 3 No.2), and 200 ms leaves the driver over 100 ms to start answering.
inline constexpr Millis kReplyTimeout{200};
static_assert(kReplyTimeout > 3 * 13 * kCharacterTime);
inline constexpr std::uint8_t kAttempts = 3;
// Not in the document: 10 ms of line silence before each frame, 2.4 characters.
inline constexpr Millis kInterFrameGap{10};
static_assert(kInterFrameGap > 2 * kCharacterTime);

class Mdriver2400Driver final : public DriverBase {
 public:
  Mdriver2400Driver(std::uint8_t address, const Settings& settings, Millis poll_interval);

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  enum class Phase : std::uint8_t { check, ready, fixed_code_error };
  enum class Awaiting : std::uint8_t { nothing, check, run };
  // What a write puts in force once the drive has confirmed it.
  enum class Change : std::uint8_t { run, stop, reset, setpoint };
  struct Pending {
    Change change = Change::setpoint;
    std::uint8_t setpoint_code = 0;  // Change::setpoint: the code asked for
    std::uint8_t sent_code = 0;      // the D4 that carries it, once on the line
  };
  using Writes = WriteLedger<Pending>;

  // driver.cpp
  [[nodiscard]] bool device_error() const;
  [[nodiscard]] std::uint8_t code_in_force() const;
  [[nodiscard]] Exchange make_exchange(Bytes frame) const;
  Exchange run_exchange(std::uint8_t code, TimePoint now);
  RxKind on_check_reply(const Frame& f, TimePoint now);
  RxKind on_run_reply(const Frame& f);
  void refresh();
  // driver_writes.cpp
  [[nodiscard]] Proposed in_force() const;
  [[nodiscard]] WriteCheck judge(const WriteOp& op, const Proposed& p) const;
  [[nodiscard]] std::optional<std::uint8_t> code_of(const Pending& w) const;
  std::optional<Exchange> next_write(TimePoint now);
  void confirm(const RunReply& r);
  void fail_sent(WriteResult r);

  Settings settings_;
  std::uint8_t address_;
  Millis cadence_;
  Phase phase_ = Phase::check;
  Awaiting awaiting_ = Awaiting::nothing;
  TimePoint next_due_{};  // epoch: at once
  // In force: what the drive has confirmed, and a setpoint stored while stopped. Only these go
  // out with the keep-alive, so a write that failed is undone on the drive too.
  Command command_ = Command::stop;  // stop or run_forward
  std::optional<std::uint8_t> setpoint_code_;
  std::optional<RunReply> last_;
  std::optional<std::uint8_t> sent_code_;
  Writes writes_{completions_};  // oldest first; only the first one is ever on the line
};

}  // namespace drivegate::mdriver
