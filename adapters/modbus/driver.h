// The modbus driver: a Modbus RTU / ASCII master that polls a slave as its profile describes.
// The profile's points are read in the planner's blocks, each group of points at its own poll
// interval; the common block follows the profile's bindings; writes go out as FC 05 / 06 / 16 and
// are in force once the slave's echo confirmed them.
//
// Freshness. The drive's state (speed, run and fault bits, fault code) may come in several
// blocks: it is as old as the oldest of them (state_read_at(), DriverTraits::state_in_parts).
// The blocks of one cycle (those due at once, and the reads of a search among them) are
// published together once the last of them was answered or failed (publish()): a PLC never
// reads one block's fault bit beside the fault code of the cycle before. A
// block the slave refuses or leaves unanswered is asked again at its next cycle, then backed off
// (twice the wait each time, at most the comm timeout), its own points unknown meanwhile, never
// left at their last value.
//
// Gaps that heal. A block the slave refuses with exception 02 (illegal data address) may cover a
// register it does not serve: a gap read through by max_gap, or a point it lacks. A block never
// read yet is searched at its first such refusal, one read before at its kRefusalsBeforeSearch-th
// in a row (a drive that refuses while busy is not taken for one that lacks a register):
// GapSearch finds the refused registers, which are skipped from then on, and the rest of the
// points are read in the largest blocks that avoid them. A slave that refuses two parts before it
// answered any read refuses everything (it is failing, or not the device the profile describes):
// nothing is skipped, the search ends, and none begins again until it answers a read; its blocks
// are backed off as failed reads, and it goes comm_lost. A point the slave
// refuses stays unknown; the new plan is logged once (take_notices). What is skipped stays
// skipped until the driver is made anew (drivegated restarts, or a reload changes the device):
// comm_lost and a return do not bring it back, so a plan is never learned in a loop.
//
//   driver.cpp         the poll plan, the line side, replies into points and the common state
//   driver_writes.cpp  check() and apply(), the writes waiting for the line, their confirmation
#pragma once

#include <algorithm>
#include <deque>
#include <map>
#include <optional>
#include <vector>

#include "codec.h"
#include "drivegate/driver_base.h"
#include "drivegate/write_ledger.h"
#include "gap_search.h"
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
  [[nodiscard]] Owed owed() const override;
  void take_over(const Owed& owed) override;

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
    // A command's values, written in order, each confirmed before the next (`words` is the one
    // at `step`); the command is in force when the last is.
    std::vector<std::uint16_t> sequence;
    std::vector<std::size_t> points;  // the point of each of `sequence`; `point` is the step's
    std::size_t step = 0;
    // A write to a drive its set value runs (setpoint_rpm runs = true): a command or a setpoint.
    // A command and a setpoint do not overtake each other (a setpoint held for the next run is
    // never lost to a stop, nor a run to a setpoint); a newer run or stop overtakes an older one,
    // whichever points each writes (a stop of its own beside a run by the set value).
    bool runs = false;
    // A run a client asked for with the trip in view (apply, from WriteOp::fault_seen): that trip
    // does not end it (update_common), so that a PLC re-sending run is not answered by the trip's
    // stop each cycle.
    bool asked_in_trip = false;

    // Whether this write puts a value in `p`.
    [[nodiscard]] bool writes_to(std::size_t p) const {
      return p == point || std::find(points.begin(), points.end(), p) != points.end();
    }
    // Whether this write and `other` put values in one point: the newer overtakes the older.
    [[nodiscard]] bool meets(const Write& other) const {
      if (runs && other.runs) {
        const bool setpoint = change == Change::setpoint;
        if (setpoint != (other.change == Change::setpoint)) return false;
        // A run and a stop, whichever points each writes (a stop of its own beside a run by the
        // set value); a reset neither overtakes them nor is overtaken by them (its first step
        // writes the set value too); two resets meet by their points.
        const auto reset = [](const Write& w) { return w.command == Command::reset_fault; };
        if (!setpoint && reset(*this) != reset(other)) return false;
        if (!setpoint && !reset(*this)) return true;
      }
      return writes_to(other.point) || std::any_of(other.points.begin(), other.points.end(),
                                                   [this](std::size_t p) { return writes_to(p); });
    }
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
    int illegal = 0;              // of those, refused with exception 02
  };
  struct Job {
    std::optional<Block> read;
    bool probe = false;                  // a read of searches_.front()
    std::optional<Writes::Entry> write;  // out of the ledger while on the line
    std::uint8_t function = 0;
    // A user-defined write code's layout ({} for the protocol's codes): its reply is that of
    // `like`, and an echo or exception under `like`'s own code is its reply too.
    CodeLayout layout;
    Bytes pdu;

    // Whether `reply_function` answers this job, and whether as an exception.
    [[nodiscard]] bool answered_by(std::uint8_t reply_function) const;
    [[nodiscard]] bool refused_by(std::uint8_t reply_function) const;
  };

  // driver.cpp
  void plan(Group& g) const;
  [[nodiscard]] Exchange exchange(const Job& j) const;
  [[nodiscard]] Micros inter_frame_gap() const;
  [[nodiscard]] Millis turn() const;
  [[nodiscard]] Millis send_limit() const;
  [[nodiscard]] Job read_job(const Block& b) const;
  void on_read(const Block& b, ByteView pdu, TimePoint now);
  // After a read's answer or failure: at the cycle's end, what it read is published.
  void end_of_read();
  void publish();
  // The slave answered `b` with exception `code`, or (nothing) not at all.
  void on_read_failed(const Block& b, std::optional<std::uint8_t> code);
  // Whether a block refused with exception 02 is to be searched for what the slave refuses.
  [[nodiscard]] bool to_search(const Block& b) const;
  // searches_.front()'s read was answered: refused with exception 02, or read.
  void on_probe(bool refused);
  // A search is over: what it found refused is skipped, and the plan made anew.
  void learn(const GapSearch& s);
  // The refused block's points sit out cycles of their back-off (on_read_failed).
  void back_off(const Block& b);
  [[nodiscard]] std::string plan_text() const;
  [[nodiscard]] Millis interval_of(std::size_t point) const;
  void update_common();
  void adopt();
  [[nodiscard]] std::optional<double> engineering(std::optional<std::size_t> point) const;
  [[nodiscard]] std::optional<bool> bit_of(const std::optional<BitBinding>& b) const;

  // driver_writes.cpp
  [[nodiscard]] std::optional<Write> write_of(const WriteOp& op) const;
  [[nodiscard]] WriteCheck judge(const WriteOp& op, const Proposed& p) const;
  // The registers setpoint_rpm's point takes for `rpm`; nothing outside its range.
  [[nodiscard]] std::optional<std::vector<std::uint16_t>> setpoint_words(double rpm) const;
  // What a run of a drive its set value runs writes for `rpm`; nothing where that is 0 (nothing
  // to run at) or beyond the set value's range.
  [[nodiscard]] std::optional<std::vector<std::uint16_t>> run_words(double rpm) const;
  // A drive run by its set value (setpoint_rpm runs = true): the setpoint the next run writes,
  // the newest of those waiting or on the line, else the one in force.
  [[nodiscard]] std::int32_t held_setpoint() const;
  // Whether a setpoint applied now is held at once rather than waiting for the line.
  [[nodiscard]] bool holds_setpoint_now() const;
  // A write first in line, decided from what is in force now: sent (true), or settled here.
  bool ready_to_send(Writes::Entry& e);
  // A drive its set value runs tripped while a run was in force (or was found tripped at start
  // with its set value not 0): its stop, the driver's own write (no ticket), so that the fault
  // clearing does not restart the motor at its set value; none while a stop is on its way.
  void stop_after_trip();
  // A command of a drive its set value runs waiting for the line or on it.
  [[nodiscard]] bool on_its_way(Command command) const;
  void settle_waiting_runs();
  void check_tripped_at_start();
  // A fault shown other than sensor_fault (a speed it cannot read is no trip).
  [[nodiscard]] bool tripped() const;
  [[nodiscard]] Job write_job(const Writes::Entry& e) const;
  static void skip_the_way_in(Write& w);
  void confirm(const Job& j, ByteView pdu);
  void put_in_force(const Write& w);
  void fail_inflight();

  Profile profile_;
  // The points' own write codes (write_layouts): every reply is delimited with them, so that an
  // echo arriving late, after its write timed out, is still taken whole (and is foreign).
  std::vector<CodeLayout> layouts_;
  // rpm = engineering value x factor + offset (the profile's rpm_factor and rpm_offset with the
  // device's options).
  RpmScale speed_scale_;
  RpmScale setpoint_scale_;
  std::string files_read_;
  std::uint8_t address_;
  Timing timing_;
  Millis poll_interval_;
  std::vector<std::size_t> exposed_;  // points_[i] is profile point exposed_[i]
  std::vector<std::optional<std::size_t>> exposed_index_;  // and back; nothing when bound

  std::vector<std::optional<std::vector<std::uint16_t>>> raw_;  // per profile point, last read
  std::vector<Reading> reading_;                                // per profile point
  // Points read in the cycle under way, and when: published at its end (publish()).
  std::vector<std::pair<std::size_t, TimePoint>> unpublished_;
  Skipped skipped_;                 // registers (and bits) the slave refuses: never read
  std::vector<bool> refused_;       // per profile point: the slave refuses it, never read
  std::deque<GapSearch> searches_;  // blocks refused with 02, searched one after the other
  bool served_ = false;             // a read was answered since the start or comm_lost
  bool refusing_ = false;           // refuses everything: no search until a read is answered
  bool plan_changed_ = false;       // not yet logged
  // The profile points the drive's state is made of (speed, run and fault bits, fault code).
  std::vector<std::size_t> state_points_;
  std::vector<Group> groups_;
  std::deque<Block> reads_;
  Writes writes_{completions_};  // waiting for the line, oldest first
  std::optional<Job> inflight_;
  TimePoint last_now_{};
  std::size_t blocks_read_ = 0;  // since the last (re)connect
  bool adopting_ = true;
  // When the fault bit was first read set beside a code saying none (update_common).
  std::optional<TimePoint> bit_set_at_;
  // The faults shown come from reads since the start or the last comm loss (update_common's
  // race rule never keeps a kind read before a loss).
  bool faults_read_ = false;
  // A stop the driver owes a drive its set value runs, after a trip (stop_after_trip): until the
  // drive confirms a stop, or a client's run.
  bool stop_owed_ = false;
  // When the fault shown now was first shown (update_common's `active`, a fault that ends a run);
  // none while no fault is shown. A client's run whose last read showed a fault at or after it
  // (WriteOp::fault_seen) was asked with the trip in view.
  std::optional<TimePoint> trip_shown_at_;
  // The run in force was asked for with the trip shown (Write::asked_in_trip): that trip does not
  // end it; the next read showing no trip does (a later trip is a new one).
  bool run_in_trip_ = false;
  bool start_checked_ = false;  // check_tripped_at_start() done
  // The setpoint held for a drive its set value runs, taken over from the driver a reload replaced
  // (Owed): adoption keeps it over a set value reading 0.
  std::optional<std::int32_t> setpoint_taken_over_;
  // The owed stop's tries: not written again before `stop_retry_at_`, the wait doubling from the
  // poll interval up to the comm timeout; the first failure is logged once.
  int stop_tries_ = 0;
  TimePoint stop_retry_at_{};
};

}  // namespace drivegate::modbus_device
