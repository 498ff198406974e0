// Writes. The drive answers every write it takes: a 06 with its echo, a 10 with the first six
// bytes of the request (document, "06H", "10H"), and one it will not take with a Modbus
// exception. So a write that needs the line is in force once that answer came back: an echo
// carrying the value sent, or a 10 reply carrying the quantity sent. Until then, and when it
// fails (an exception, no answer, superseded, never sent in time), what was in force stays.
// A setpoint while the motor is stopped needs no line: the reference travels with the next run
// command (one 10 write, as the document's run examples do), so it is in force at once.
#include <algorithm>
#include <cmath>

#include "driver.h"
#include "faults.h"
#include "points.h"

namespace drivegate::ed3100 {

// What a part asks for, in the driver's terms; nothing when the drive cannot be asked it.
std::optional<Ed3100Driver::Write> Ed3100Driver::write_of(const WriteOp& op) const {
  Write w;
  switch (op.target) {
    case WriteOp::Target::command:
      switch (op.command) {
        case Command::run_forward:
        case Command::run_reverse:
        case Command::stop:
          w.command = op.command;
          break;
        case Command::quick_stop:  // the document has no faster stop than 0x0001
          w.command = Command::stop;
          break;
        case Command::reset_fault:
          w.change = Change::reset;
          break;
      }
      return w;
    case WriteOp::Target::setpoint: {
      const auto centi = centi_hz_from_rpm(op.rpm);
      if (!centi) return std::nullopt;
      w.change = Change::reference;
      w.value = *centi;
      w.rpm = op.rpm;
      return w;
    }
    case WriteOp::Target::forward:  // only ever handed to a driver that forwards()
      return std::nullopt;
    case WriteOp::Target::point:
      break;
  }
  // The point's engineering value; the gateway has checked it against the point's limits.
  if (!std::holds_alternative<std::int64_t>(op.value) &&
      !std::holds_alternative<double>(op.value)) {
    return std::nullopt;
  }
  const double x = as_double(op.value);
  if (op.point == pt::frequency_setpoint) {
    const long long centi = std::llround(x * 100.0);  // 0x2001 in 0.01 Hz
    if (centi < 0 || centi > 0xFFFF) return std::nullopt;
    w.change = Change::reference;
    w.value = static_cast<std::uint16_t>(centi);
    w.rpm = rpm_from_hz(static_cast<double>(centi) * 0.01);
    return w;
  }
  const std::size_t first = pt::parameter(settings_, 0);
  if (op.point < first || op.point >= first + settings_.parameters.size()) return std::nullopt;
  const double raw = std::round(x);
  if (raw < 0 || raw > 0xFFFF) return std::nullopt;  // one 16-bit register
  w.change = Change::parameter;
  w.slot = op.point - first;
  w.value = static_cast<std::uint16_t>(raw);
  return w;
}

// One part of a request. Whether the drive can take a part depends on nothing the parts before
// it leave in force, only on a trip, which changes with what the line brings alone.
WriteCheck Ed3100Driver::judge(const WriteOp& op) const {
  if (!write_of(op)) return WriteCheck::invalid_value;
  // A tripped drive cannot run: refuse rather than send a run it answers with an exception.
  if (op.target == WriteOp::Target::command && is_run(op.command) && tripped(fault_word_)) {
    return WriteCheck::refused;
  }
  return WriteCheck::ok;
}

WriteCheck Ed3100Driver::check(std::span<const WriteOp> request) const {
  return check_in_order(request, Proposed{common_.command, common_.setpoint_rpm},
                        [this](const WriteOp& op, const Proposed&) { return judge(op); });
}

WriteStatus Ed3100Driver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  last_now_ = now;
  writes_.expire_after(now);
  adopting_ = false;  // a client decides from now on
  if (const auto no = refusal(judge(op))) return *no;
  const Write w = *write_of(op);  // judge() found it
  // A newer write to the same register wins: the older one, still waiting for the line, never
  // reaches the drive (a run then a stop in quick succession never starts the motor).
  const std::uint16_t reg = register_of(w);
  writes_.settle_if([&](const Writes::Entry& e) { return register_of(e.job) == reg; },
                    WriteResult::no_response);
  // Stopped, with no run on its way to the drive: stored.
  if (w.change == Change::reference && !drive_runs() && !run_under_way()) {
    set_reference(w.value, w.rpm);
    return WriteStatus::done;
  }
  // Not on the line by then, it is failed and never sent: by then the gateway could not have its
  // answer before its own deadline, and a run the PLC was told failed must not start the motor
  // later (writes_.expire_after()).
  writes_.push(w, t, now + send_limit());
  return WriteStatus::pending;
}

// The motor turns, or a run is in force: a new reference has to go to 0x2001 now.
bool Ed3100Driver::drive_runs() const {
  return is_run(common_.command) || common_.running;
}

// A run waiting for the line or on it: once taken, a reference would have to go to 0x2001.
bool Ed3100Driver::run_under_way() const {
  const auto run = [](const Writes::Entry& e) {
    return e.job.change == Change::command && is_run(e.job.command);
  };
  return std::any_of(writes_.begin(), writes_.end(), run) ||
         (inflight_ && inflight_->write && run(*inflight_->write));
}

std::uint16_t Ed3100Driver::register_of(const Write& w) const {
  switch (w.change) {
    case Change::command:
      return kRegCommand;
    case Change::reset:
      return settings_.reset_register;
    case Change::reference:
      return kRegFrequency;
    case Change::parameter:
      break;
  }
  return settings_.parameters.at(w.slot);
}

// The frame that carries a write, worked out once it is first in line, from what is in force
// then (a write ahead of it may have been confirmed or failed meanwhile). Nothing: it needs none.
std::optional<Ed3100Driver::Job> Ed3100Driver::job_of(const Writes::Entry& e) const {
  const Write& w = e.job;
  Job j;
  j.op = Op::write;
  j.reg = register_of(w);
  j.write = e;
  switch (w.change) {
    case Change::command:
      if (is_run(w.command)) {
        // Command and the reference in force in one 10 write, as the document's examples do.
        j.words = {w.command == Command::run_forward ? kCmdForward : kCmdReverse, reference_};
      } else {
        j.words = {kCmdStop};
      }
      break;
    case Change::reset:
      j.words = {settings_.reset_value};
      break;
    case Change::reference:
      if (!drive_runs()) return std::nullopt;  // the next run carries it
      j.words = {w.value};
      break;
    case Change::parameter:
      j.words = {w.value};
      break;
  }
  return j;
}

std::optional<Ed3100Driver::Job> Ed3100Driver::next_write() {
  while (!writes_.empty()) {
    const Writes::Entry e = writes_.take_front();
    if (std::optional<Job> j = job_of(e)) return j;
    // A reference that finds the motor stopped: stored, in force at once.
    put_in_force(e.job);
    writes_.settle(e, WriteResult::ok);
  }
  return std::nullopt;
}

// The drive's answer to the write on the line.
void Ed3100Driver::confirm(const Job& j, const Reply& r) {
  const Writes::Entry& e = *j.write;
  if (r.kind == ReplyKind::exception) {
    writes_.settle(e, WriteResult::refused);
    return;
  }
  // 06: the echo carries the value the register took; 10: the quantity of registers written.
  const bool took = j.words.size() > 1 ? r.value == j.words.size() : r.value == j.words.at(0);
  if (!took) {
    writes_.settle(e, WriteResult::refused);
    return;
  }
  put_in_force(e.job);
  writes_.settle(e, WriteResult::ok);
}

void Ed3100Driver::put_in_force(const Write& w) {
  switch (w.change) {
    case Change::command:
      common_.command = w.command;
      // The drive has taken the run: the next status read shows the motor as it is.
      if (is_run(w.command)) common_.running = true;
      break;
    case Change::reset:
      break;  // the fault it clears shows in the next status read
    case Change::reference:
      set_reference(w.value, w.rpm);
      break;
    case Change::parameter:
      values_[pt::parameter(settings_, w.slot)] = static_cast<std::int64_t>(w.value);
      // Read back, ahead of the polls: the register shows what the drive holds.
      if (!broadcast()) {
        reads_.push_front(read_job(Op::read_param, w.slot, settings_.parameters.at(w.slot)));
      }
      break;
  }
}

void Ed3100Driver::set_reference(std::uint16_t centi_hz, std::int32_t rpm) {
  reference_ = centi_hz;
  common_.setpoint_rpm = rpm;
  values_[pt::frequency_setpoint] = centi_hz * 0.01;
}

// The exchange on the line ended without an answer to the write it carried, if any.
void Ed3100Driver::fail_inflight() {
  if (inflight_ && inflight_->write) writes_.settle(*inflight_->write, WriteResult::no_response);
  inflight_.reset();
}

}  // namespace drivegate::ed3100
