// The stateful half of the adapter: one eDrive (one device id) on a shared RS-485 line. Reads
// Build Information and Running Limits at start-up and after every comm loss, then polls Status.
// Its writes, Set Run State and Acknowledge Faults, are never acknowledged ("Command": "Write
// commands are not acknowledged ... success/fail can be determined by other means"): they go out
// with ReplyMode::none, and the status reads that follow decide whether the drive took them.
// `command` and `setpoint_rpm` change only then (README.md, "Writes and their confirmation").
//
//   driver.cpp         the poll plan, replies into points and the common state
//   driver_writes.cpp  check() and apply(), the writes waiting for the line, their confirmation
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "payloads.h"
#include "settings.h"

namespace drivegate::unicla {

// Not in the document, which gives no turnaround time: 5 ms (9.6 characters at 19200 baud) of
// line silence before each frame, slack for the drive's transceiver to turn around.
inline constexpr Millis kInterFrameGap{5};
static_assert(kInterFrameGap > 9 * kCharacterTime);
// The document states no timeout: comm_lost after max(3 s, 4 polls + one read's attempts).
inline constexpr Millis kMinCommTimeout{3000};
// The gateway fails a write this long after the driver's own deadline (confirm_timeout_ms), so
// that the PLC always gets the driver's verdict.
inline constexpr Millis kWriteTimeoutSlack{1000};
// While a write waits for the status that confirms it, the status is read this often rather than
// at the poll interval: a write is decided soon after the drive shows it, whatever poll_ms is.
inline constexpr Millis kConfirmPoll{100};
// The Status has no setpoint echo: a speed change counts as taken once the speed is within this
// of the target, or closer to it than when the write went out.
inline constexpr std::int32_t kSpeedToleranceRpm = 50;
// The default reply_timeout_ms covers the longest read reply on the wire, Build Information
// ("Message Structure": SOF, 8 header bytes, 80 payload bytes, 2 CRC bytes, EOF, unstuffed).
static_assert(Settings{}.reply_timeout >
              static_cast<long>(1 + kHeaderSize + kBuildInfoSize + kCrcSize + 1) * kCharacterTime);

class EDriveDriver final : public DriverBase {
 public:
  EDriveDriver(std::uint8_t address, Millis poll_interval, const Settings& settings);

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  enum class Phase : std::uint8_t { build_information, running_limits, polling };
  // What a write frame asks of the drive, and so which status shows that the drive took it.
  enum class Change : std::uint8_t {
    run,          // Set Run State <setpoint>: run_forward
    stop,         // Set Run State 0: stop, quick_stop, and the undoing of a failed run
    speed,        // Set Run State <rpm> while a run is in force: setpoint_rpm
    acknowledge,  // Acknowledge Faults: reset_fault
  };
  struct Awaiting {
    MessageId id;
    std::uint8_t sequence;
  };
  struct SpeedLimits {
    std::uint16_t min = 0;
    std::uint16_t max = 0;
  };
  // A write the drive has not shown it took yet. The ledger keeps the writes it carries out (none:
  // the undoing of a failed run), its deadline (confirm_timeout after it was applied) and whether
  // it went out.
  struct Pending {
    Change change = Change::stop;
    std::uint16_t rpm = 0;    // what Set Run State carries: 0 stops
    std::uint64_t order = 0;  // when it was applied, across the two kinds of write
    // When it went out, for the statuses after it to be judged against.
    bool was_running = false;
    std::int32_t rpm_at_send = 0;
    bool saw_status = false;  // a status came back after it went out
  };
  using Writes = WriteLedger<Pending>;

  // driver.cpp
  Frame request(CommandByte cmd, MessageId id, Bytes payload = {});
  [[nodiscard]] TimePoint poll_due() const;
  Exchange read(TimePoint now);
  RxKind on_reply(MessageId id, const Frame& f, TimePoint now);
  void on_status(const Status& s, TimePoint now);
  [[nodiscard]] bool drive_runs() const;
  // driver_writes.cpp
  [[nodiscard]] Proposed in_force() const;
  [[nodiscard]] WriteCheck judge(const WriteOp& op, const Proposed& p) const;
  [[nodiscard]] bool control_disabled() const;
  [[nodiscard]] bool has_unsent_write() const;
  [[nodiscard]] bool awaiting_confirmation() const;
  [[nodiscard]] TimePoint earliest_deadline() const;
  Pending make_pending(Change change, std::uint16_t rpm);
  [[nodiscard]] TimePoint deadline_from(TimePoint now) const;
  bool join(Change change, std::uint16_t rpm, Ticket t);
  WriteStatus apply_setpoint(std::uint16_t rpm, Ticket t, TimePoint now);
  WriteStatus apply_run_state(Change change, std::uint16_t rpm, Ticket t, TimePoint now);
  WriteStatus apply_acknowledge(Ticket t, TimePoint now);
  std::optional<Exchange> next_write(TimePoint now);
  Exchange send(Writes::Entry& e, TimePoint now);
  void settle_front();
  void confirm(const Status& s, TimePoint now);
  [[nodiscard]] std::optional<WriteResult> verdict(const Pending& w, const Status& s) const;
  void take_effect(const Pending& w);
  void finish_front(WriteResult r, TimePoint now);
  void settle_ack(WriteResult r);
  void expire(TimePoint now);
  void fail_all();

  std::uint8_t address_;
  Millis poll_interval_;
  Settings settings_;
  // common_ (DriverBase): its command and setpoint_rpm are what the drive holds, set when a
  // status confirmed a write, or when a setpoint is stored while no run is in force; nothing else
  // touches them.

  Phase phase_ = Phase::build_information;
  std::uint8_t sequence_ = 0;
  std::optional<Awaiting> awaiting_;
  TimePoint next_poll_{};  // epoch: at once
  TimePoint last_read_{};
  SpeedLimits build_speed_{};  // Build Information min / max, the fallback
  std::optional<SpeedLimits> limits_;
  bool adopting_ = true;  // until the first status, or a write: a running drive is shown running
  std::optional<std::uint8_t> control_enabled_;
  std::optional<Status> status_;

  // Set Run State, oldest first; only the front is on the line.
  Writes run_writes_{completions_};
  std::optional<Writes::Entry> ack_;  // Acknowledge Faults, settled through run_writes_
  std::uint64_t next_order_ = 0;
};

}  // namespace drivegate::unicla
