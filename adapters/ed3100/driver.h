// The ED3100 driver: a Modbus RTU master that reads the drive's parameters at start-up, then
// polls the fault/state word and the chosen monitors, and translates commands and writes.
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include "codec.h"
#include "config.h"
#include "drivegate/driver.h"
#include "registers.h"

namespace drivegate::ed3100 {

class Ed3100Driver final : public Driver {
 public:
  Ed3100Driver(Config config, Millis poll_interval);

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
  enum class Op : std::uint8_t {
    read_fault,
    read_monitor,
    read_param,
    write_command,
    write_frequency,
    write_param,
    write_reset
  };

  // One transaction, queued or on the line.
  struct Job {
    Op op = Op::read_fault;
    std::size_t slot = 0;  // monitor or parameter index
    std::uint16_t reg = 0;
    std::vector<std::uint16_t> words;  // writes: the values
    std::optional<Ticket> ticket;
    Command command = Command::stop;  // write_command: what it means once confirmed

    static Job make(Op op, std::size_t slot, std::uint16_t reg,
                    std::vector<std::uint16_t> words = {}) {
      Job j;
      j.op = op;
      j.slot = slot;
      j.reg = reg;
      j.words = std::move(words);
      return j;
    }
  };

  [[nodiscard]] bool broadcast() const { return config_.address == kBroadcast; }
  [[nodiscard]] ReplyShape shape(const Job& j) const;
  [[nodiscard]] Exchange exchange(const Job& j) const;
  void start_cycle(TimePoint now);
  void apply(const Job& j, const Reply& r);
  void apply_fault(const std::vector<std::uint16_t>& w);
  void apply_monitor(std::size_t slot, const std::vector<std::uint16_t>& w);
  void complete(const Job& j, WriteResult r);
  void update_ready();
  void update_speed();
  WriteStatus queue_write(Job j, Ticket t);
  WriteStatus set_frequency(std::uint16_t centi_hz, std::int32_t rpm, Ticket t);
  [[nodiscard]] std::int32_t rpm_from_hz(double hz) const;
  [[nodiscard]] std::optional<std::uint16_t> centi_hz_from_rpm(std::int32_t rpm) const;

  Config config_;
  Millis poll_interval_;
  std::vector<PointSpec> points_;
  std::vector<Value> values_;
  CommonState common_;

  std::deque<Job> writes_;
  std::deque<Job> reads_;
  std::optional<Job> inflight_;
  std::vector<Completion> completions_;
  TimePoint next_cycle_{};
  TimePoint last_now_{};
  std::vector<bool> param_known_;  // answered since the last (re)connect
  bool fault_known_ = false;       // 0x0E01 answered since the last (re)connect
  std::uint16_t fault_word_ = kNoFault;
  std::uint16_t state_word_ = 0;
  std::uint16_t frequency_ = 0;     // 0x2001 reference, 0.01 Hz
  std::optional<double> speed_hz_;  // the speed monitor's last value
  bool speed_stopped_ = true;       // its format word's "stopped" bit
};

}  // namespace drivegate::ed3100
