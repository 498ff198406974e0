// The modbus driver: a Modbus RTU / ASCII master that polls a slave as its profile describes.
// The profile's points are read in the planner's blocks, each group of points at its own poll
// interval; the common block follows the profile's bindings; writes go out as FC 05 / 06 / 16 and
// are in force once the slave's echo confirmed them.
//
// Freshness. The drive's state (speed, run and fault bits, fault code) may come in several
// blocks: it is as old as the oldest of them (state_read_at(), DriverTraits::state_in_parts). A
// block the slave refuses or leaves unanswered is asked again at its next cycle, then backed off
// (twice the wait each time, at most the comm timeout), its own points unknown meanwhile, never
// left at their last value.
//
//   driver.cpp         the poll plan, the line side, replies into points and the common state
//   driver_writes.cpp  check() and apply(), the writes waiting for the line, their confirmation
#pragma once

#include <deque>
#include <map>
#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "planner.h"
#include "profile.h"

namespace drivegate::modbus_device {

// How the driver uses the line, beside what the profile says.
struct Timing {
  std::uint8_t attempts = 3;
  Millis comm_timeout{3000};
  // One character on the line as the bus runs it: the RTU silence between frames (3.5
  // characters, 1.75 ms above 19200 baud: Serial Line 2.5.1.1) and the time replies take.
  std::chrono::nanoseconds char_time{0};
};

class ModbusDriver final : public DriverBase {
 public:
  // `address`: 1..247 (Serial Line 2.2).
  // `files_read`: the profile as Driver::files_read says it (settings.h, profile_read).
  ModbusDriver(std::uint8_t address, Profile profile, Timing timing, Millis poll_interval,
               std::string files_read = {});

  DRIVEGATE_DRIVER_OVERRIDES;
  [[nodiscard]] std::optional<TimePoint> state_read_at() const override;
  [[nodiscard]] std::string files_read() const override { return files_read_; }

  // Which profile point each of points() is.
  [[nodiscard]] std::size_t profile_point(std::size_t point) const { return exposed_.at(point); }
  // Cycles of its group a profile point sits out after failed reads (refused, unanswered).
  [[nodiscard]] int backed_off(std::size_t profile_point) const {
    return reading_.at(profile_point).skip;
  }

 private:
  // A write, in the slave's terms: the words for a profile point, and what it puts in force. Its
  // ticket, and the time it must be on the line by (not by then: failed, and never sent), are the
  // ledger's.
  enum class Change : std::uint8_t { command, setpoint, point };
  struct Write {
    Change change = Change::point;
    std::size_t point = 0;             // profile point written
    std::vector<std::uint16_t> words;  // registers (or, for a coil, {0 or 1})
    Command command = Command::stop;   // Change::command
    std::int32_t rpm = 0;              // Change::setpoint
  };
  using Writes = WriteLedger<Write>;
  // Points polled at one interval, and the blocks that read them.
  struct Group {
    Millis interval{0};
    std::vector<std::size_t> points;
    std::vector<Block> blocks;
    TimePoint due{};
  };
  // A profile point's reads since the driver started or comm was lost.
  struct Reading {
    std::optional<TimePoint> at;  // its last good read
    int failures = 0;             // reads refused or unanswered in a row
    int skip = 0;                 // cycles of its group it sits out before it is asked again
  };
  struct Job {
    std::optional<Block> read;
    std::optional<Writes::Entry> write;  // out of the ledger while on the line
    std::uint8_t function = 0;
    Bytes pdu;
  };

  // driver.cpp
  void plan(Group& g) const;
  [[nodiscard]] Exchange exchange(const Job& j) const;
  [[nodiscard]] Millis inter_frame_gap() const;
  [[nodiscard]] Millis turn() const;
  [[nodiscard]] Millis send_limit() const;
  [[nodiscard]] Job read_job(const Block& b) const;
  void on_read(const Block& b, ByteView pdu, TimePoint now);
  // The slave answered `b` with exception `code`, or (nothing) not at all.
  void on_read_failed(const Block& b, std::optional<std::uint8_t> code);
  [[nodiscard]] Millis interval_of(std::size_t point) const;
  void update_common();
  void adopt();
  [[nodiscard]] std::optional<double> engineering(std::optional<std::size_t> point) const;
  [[nodiscard]] std::optional<bool> bit_of(const std::optional<BitBinding>& b) const;

  // driver_writes.cpp
  [[nodiscard]] std::optional<Write> write_of(const WriteOp& op) const;
  [[nodiscard]] WriteCheck judge(const WriteOp& op) const;
  [[nodiscard]] Job write_job(const Writes::Entry& e) const;
  void confirm(const Job& j, ByteView pdu);
  void put_in_force(const Write& w);
  void fail_inflight();

  Profile profile_;
  std::string files_read_;
  std::uint8_t address_;
  Timing timing_;
  Millis poll_interval_;
  std::vector<std::size_t> exposed_;  // points_[i] is profile point exposed_[i]
  std::vector<std::optional<std::size_t>> exposed_index_;  // and back; nothing when bound

  std::vector<std::optional<std::vector<std::uint16_t>>> raw_;  // per profile point, last read
  std::vector<Reading> reading_;                                // per profile point
  std::vector<bool> alone_;  // per profile point: read on its own after a refused block
  // The profile points the drive's state is made of (speed, run and fault bits, fault code).
  std::vector<std::size_t> state_points_;
  std::vector<Group> groups_;
  std::deque<Block> reads_;
  Writes writes_{completions_};  // waiting for the line, oldest first
  std::optional<Job> inflight_;
  TimePoint last_now_{};
  std::size_t blocks_read_ = 0;  // since the last (re)connect
  bool adopting_ = true;
};

}  // namespace drivegate::modbus_device
