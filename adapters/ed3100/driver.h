// The ED3100 driver: a Modbus RTU master that reads the drive's parameters at start-up, then polls
// the fault/state word and the chosen monitors; writes go out as 06 / 10 and are in force once the
// drive's reply confirmed them.
//
//   driver.cpp         the poll plan, the line side, replies into points and the common state
//   driver_writes.cpp  check() and apply(), the writes waiting for the line, their confirmation
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "registers.h"
#include "settings.h"

namespace drivegate::ed3100 {

// Not in the document, which gives no baud table: the time on the wire allowed per attempt for
// a request and its reply. The longest pair, a 13-byte 10 write and its 8-byte reply, takes
// 96 ms at 2400 baud 8E1 (11 bits a character).
inline constexpr Millis kWireAllowance{100};

class Ed3100Driver final : public DriverBase {
 public:
  Ed3100Driver(std::uint8_t address, Settings settings, Millis poll_interval);

  DRIVEGATE_DRIVER_OVERRIDES;

 private:
  // What a write puts in force once the drive confirmed it. Its ticket, and the time it must be
  // on the line by (not by then: failed, and never sent), are the ledger's.
  enum class Change : std::uint8_t { command, reset, reference, parameter };
  struct Write {
    Change change = Change::command;
    Command command = Command::stop;  // Change::command: run_forward, run_reverse or stop
    std::uint16_t value = 0;          // reference (0.01 Hz) or parameter value
    std::int32_t rpm = 0;             // Change::reference: what setpoint_rpm reads then
    std::size_t slot = 0;             // Change::parameter: index into the parameters
  };
  using Writes = WriteLedger<Write>;

  enum class Op : std::uint8_t { read_fault, read_monitor, read_param, write };
  // One transaction, queued or on the line.
  struct Job {
    Op op = Op::read_fault;
    std::size_t slot = 0;  // monitor or parameter index
    std::uint16_t reg = 0;
    std::vector<std::uint16_t> words;    // writes: the values sent
    std::optional<Writes::Entry> write;  // Op::write: what it carries, out of the ledger
  };

  // driver.cpp
  [[nodiscard]] bool broadcast() const { return address_ == kBroadcast; }
  [[nodiscard]] ReplyShape shape(const Job& j) const;
  [[nodiscard]] Exchange exchange(const Job& j) const;
  [[nodiscard]] Millis turn() const;
  [[nodiscard]] Millis send_limit() const;
  static Job read_job(Op op, std::size_t slot, std::uint16_t reg);
  void start_cycle(TimePoint now);
  void on_reply(const Job& j, const Reply& r);
  void apply_fault(const std::vector<std::uint16_t>& w);
  void apply_monitor(std::size_t slot, const std::vector<std::uint16_t>& w);
  void update_ready();
  void update_speed();
  void adopt();
  [[nodiscard]] std::int32_t rpm_from_hz(double hz) const;
  [[nodiscard]] std::optional<std::uint16_t> centi_hz_from_rpm(std::int32_t rpm) const;

  // driver_writes.cpp
  [[nodiscard]] WriteCheck judge(const WriteOp& op) const;
  [[nodiscard]] std::optional<Write> write_of(const WriteOp& op) const;
  [[nodiscard]] bool drive_runs() const;
  [[nodiscard]] bool run_under_way() const;
  [[nodiscard]] std::uint16_t register_of(const Write& w) const;
  [[nodiscard]] std::optional<Job> job_of(const Writes::Entry& e) const;
  std::optional<Job> next_write();
  void confirm(const Job& j, const Reply& r);
  void put_in_force(const Write& w);
  void set_reference(std::uint16_t centi_hz, std::int32_t rpm);
  void fail_inflight();

  Settings settings_;
  std::uint8_t address_;
  Millis poll_interval_;

  Writes writes_{completions_};  // waiting for the line, oldest first
  std::deque<Job> reads_;
  std::optional<Job> inflight_;
  TimePoint next_cycle_{};
  TimePoint last_now_{};
  std::vector<bool> param_known_;  // answered since the last (re)connect
  bool fault_known_ = false;       // 0x0E01 answered since the last (re)connect
  std::uint16_t fault_word_ = kNoFault;
  std::uint16_t state_word_ = 0;
  std::uint16_t reference_ = 0;     // 0x2001 in force, 0.01 Hz: what the next run carries
  std::optional<double> speed_hz_;  // the speed monitor's last value
  bool speed_stopped_ = true;       // its format word's "stopped" bit
  // Until the first status and speed are in, or something is written: a drive found running
  // (the gateway restarted, or this device was changed by a reload) is shown as it runs, its
  // run and speed taken as the command and setpoint in force (README, "Choices").
  bool adopting_ = true;
};

}  // namespace drivegate::ed3100
