// Writes. A Modbus slave answers every write it takes with an echo (FC 05 and 06: the request
// itself; FC 16: its address and quantity; Application Protocol 6.5, 6.6, 6.12) and one it will
// not take with an exception. So a write is in force once its echo came back; until then, and
// when it fails (an exception, no answer, superseded, never sent in time), what was in force
// stays.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "driver.h"
#include "values.h"

namespace drivegate::modbus_device {
namespace {

// FC 05 writes a coil ON as 0xFF00 and OFF as 0x0000 (Application Protocol 6.5).
constexpr std::uint16_t kCoilOn = 0xFF00;

}  // namespace

// What a part asks of the slave; nothing when the profile gives no way to ask it, or the value
// is not one the point can carry.
std::optional<ModbusDriver::Write> ModbusDriver::write_of(const WriteOp& op) const {
  const CommonBindings& c = profile_.common;
  Write w;
  switch (op.target) {
    case WriteOp::Target::command: {
      // A drive its set value runs: a run writes the setpoint held there (its words once first in
      // line, ready_to_send()), a stop 0 unless the drive has a stop of its own; a set value
      // written 0 and up says no direction.
      if (c.setpoint_runs && op.command != Command::reset_fault) {
        if (op.command == Command::run_reverse) return std::nullopt;
        const bool run = op.command == Command::run_forward;
        if (run || !c.stop) {
          w.change = Change::command;
          w.runs = true;
          w.point = *c.setpoint_rpm;
          w.command = run ? Command::run_forward : Command::stop;
          if (!run) w.words = {0};
          return w;
        }
      }
      std::optional<ValueBinding> b;
      switch (op.command) {
        case Command::stop:
        case Command::quick_stop:  // a profile has no faster stop than its stop
          b = c.stop;
          w.command = Command::stop;
          break;
        case Command::run_forward:
          b = c.run_forward;
          w.command = op.command;
          break;
        case Command::run_reverse:
          b = c.run_reverse;
          w.command = op.command;
          break;
        case Command::reset_fault:
          b = c.reset_fault;
          w.command = op.command;
          break;
      }
      if (!b) return std::nullopt;
      w.change = Change::command;
      w.runs = c.setpoint_runs;
      w.points = b->points;
      w.sequence = b->sequence;
      if (w.command != Command::stop && common_.running) skip_the_way_in(w);
      w.point = w.points.front();
      w.words = {w.sequence.front()};
      return w;
    }
    case WriteOp::Target::setpoint: {
      auto words = setpoint_words(op.rpm);
      if (!words) return std::nullopt;
      w.change = Change::setpoint;
      w.point = *c.setpoint_rpm;
      w.words = std::move(*words);
      w.rpm = op.rpm;
      w.runs = c.setpoint_runs;
      return w;
    }
    case WriteOp::Target::forward:  // the pass-through driver's (passthrough.h)
      return std::nullopt;
    case WriteOp::Target::point:
      break;
  }
  if (op.point >= exposed_.size()) return std::nullopt;
  if (!std::holds_alternative<std::int64_t>(op.value) &&
      !std::holds_alternative<double>(op.value)) {
    return std::nullopt;
  }
  const ProfilePoint& p = profile_.points[exposed_[op.point]];
  if (!p.writable() || p.access == PointAccess::read) return std::nullopt;
  auto words = words_for(p, as_double(op.value));
  if (!words) return std::nullopt;
  w.change = Change::point;
  w.point = exposed_[op.point];
  w.words = std::move(*words);
  return w;
}

std::optional<std::vector<std::uint16_t>> ModbusDriver::setpoint_words(double rpm) const {
  const CommonBindings& c = profile_.common;
  if (!c.setpoint_rpm) return std::nullopt;
  const ProfilePoint& p = profile_.points[*c.setpoint_rpm];
  // A set value that runs the drive says no direction: 0 and up (run_reverse is refused).
  if (c.setpoint_runs && rpm < 0) return std::nullopt;
  double v = rpm;
  if (!c.setpoint_factor.terms.empty()) {
    // rpm -> the point's value -> raw, rounded to the point's step (docs/profiles.md,
    // "[common]"): a float point takes the value as it is.
    v = setpoint_scale_.value(v);
    if (p.type != ValueType::f32) v = std::round(v / p.scale) * p.scale;
  }
  // The point's range, after the conversion, allowing for a scale's binary fractions.
  const double slack = 1e-9 * std::max(1.0, std::fabs(v));
  if ((p.min && v < *p.min - slack) || (p.max && v > *p.max + slack)) return std::nullopt;
  return words_for(p, v);
}

std::optional<std::vector<std::uint16_t>> ModbusDriver::run_words(double rpm) const {
  auto words = setpoint_words(rpm);
  if (!words || std::all_of(words->begin(), words->end(), [](auto w) { return w == 0; }))
    return std::nullopt;
  return words;
}

// A drive its set value runs has nothing to run at while the setpoint is 0 (its set value 0 is
// its stop): such a run is refused (0x04) rather than confirmed and never turning.
WriteCheck ModbusDriver::judge(const WriteOp& op, const Proposed& p) const {
  if (!write_of(op)) return WriteCheck::invalid_value;
  if (profile_.common.setpoint_runs && op.target == WriteOp::Target::command &&
      op.command == Command::run_forward) {
    if (!run_words(p.setpoint_rpm)) return WriteCheck::refused;
  }
  return WriteCheck::ok;
}

// A drive its set value runs: a request that writes the command and the setpoint together (the
// common block's holding 0..1 in one FC 16) runs at that setpoint, whichever part comes first.
WriteCheck ModbusDriver::check(std::span<const WriteOp> request) const {
  Proposed in_force{common_.command, common_.setpoint_rpm};
  if (profile_.common.setpoint_runs) {
    in_force.setpoint_rpm = held_setpoint();
    for (const WriteOp& op : request) {
      if (op.target == WriteOp::Target::setpoint) in_force.setpoint_rpm = op.rpm;
    }
  }
  return check_in_order(request, in_force,
                        [this](const WriteOp& op, const Proposed& p) { return judge(op, p); });
}

std::int32_t ModbusDriver::held_setpoint() const {
  std::int32_t rpm = common_.setpoint_rpm;
  if (inflight_ && inflight_->write && inflight_->write->job.change == Change::setpoint)
    rpm = inflight_->write->job.rpm;
  for (const Writes::Entry& e : writes_) {
    if (e.job.change == Change::setpoint) rpm = e.job.rpm;
  }
  return rpm;
}

// Held at once only where nothing can change what is in force first: no run in force, and no
// write waiting or on the line. Otherwise it waits for the line, where ready_to_send() decides
// from what is in force then (a command ahead of it may be confirmed or fail meanwhile).
bool ModbusDriver::holds_setpoint_now() const {
  return !is_run(common_.command) && writes_.empty() && !(inflight_ && inflight_->write);
}

// First in line, a drive its set value runs decides from what is in force now. A setpoint with
// no run in force is held for the next run, never sent; with a run in force it goes to the drive,
// unless the drive already holds it (the run ahead of it wrote it). A run writes the newest
// setpoint (held, or waiting behind it: a request of command and setpoint runs at its setpoint),
// and is refused where that is 0.
bool ModbusDriver::ready_to_send(Writes::Entry& e) {
  Write& w = e.job;
  if (!w.runs) return true;
  if (w.change == Change::setpoint && !is_run(common_.command)) {
    common_.setpoint_rpm = w.rpm;
    writes_.settle(e, WriteResult::ok);
    return false;
  }
  // A reset with no run in force first sets the set value to 0: a fault cleared must not start
  // the motor at the set value the trip left (parse_profile makes it one register).
  if (w.change == Change::command && w.command == Command::reset_fault && w.step == 0 &&
      !is_run(common_.command)) {
    w.sequence.insert(w.sequence.begin(), 0);
    w.points.insert(w.points.begin(), *profile_.common.setpoint_rpm);
    w.point = w.points.front();
    w.words = {0};
  }
  if (w.change == Change::command && w.command == Command::run_forward) {
    // The setpoints waiting behind it are carried out by its frame: they settle with it.
    w.rpm = common_.setpoint_rpm;
    for (const Writes::Entry& s :
         writes_.take_if([](const Writes::Entry& x) { return x.job.change == Change::setpoint; })) {
      w.rpm = s.job.rpm;
      for (const Ticket t : s.tickets) writes_.join(e, t);
    }
    const auto words = run_words(w.rpm);
    if (!words) {
      writes_.settle(e, WriteResult::refused);
      return false;
    }
    w.words = *words;
  }
  return true;
}

WriteStatus ModbusDriver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  last_now_ = now;
  writes_.expire_after(now);
  adopting_ = false;  // a client decides from now on
  auto w = write_of(op);
  if (!w) return WriteStatus::invalid_value;
  // Asked with the trip in view: the client's last read of the fault state before it asked
  // showed a fault, and was made once this trip was shown (a read that showed an earlier fault
  // is older than this trip). A client that had not read the trip, or cannot tell, asked before.
  w->asked_in_trip = w->runs && w->change == Change::command && is_run(w->command) &&
                     trip_shown_at_ && op.fault_seen && *op.fault_seen >= *trip_shown_at_;
  if (w->runs && w->change == Change::setpoint && holds_setpoint_now()) {
    common_.setpoint_rpm = op.rpm;
    return WriteStatus::done;
  }
  // A run asked before the trip now shown, applied after it (a part that waited behind another):
  // overtaken by the trip, it is over (no_response), as one that waited in the driver when the
  // trip showed (settle_waiting_runs), and it never overtakes the stop owed.
  if (w->runs && w->change == Change::command && w->command == Command::run_forward &&
      trip_shown_at_ && !w->asked_in_trip) {
    writes_.push(std::move(*w), t, now + send_limit());
    settle_waiting_runs();
    return WriteStatus::pending;
  }
  // A newer write to the same point wins: the older one, still waiting for the line, never
  // reaches the slave (a run then a stop in quick succession never starts the motor). A command
  // whose sequence writes several points meets every write to any of them.
  writes_.settle_if([&w](const Writes::Entry& e) { return e.job.meets(*w); },
                    WriteResult::no_response);
  // Not on the line by then, it is failed and never sent: by then the gateway could not have its
  // answer before its own deadline, and a run the PLC was told failed must not start the motor
  // later (writes_.expire_after()).
  writes_.push(std::move(*w), t, now + send_limit());
  return WriteStatus::pending;
}

// FC 05 for a coil, FC 06 for one register where the profile says "single", FC 16 otherwise
// (write_function), or the point's own code of that layout (write_code).
ModbusDriver::Job ModbusDriver::write_job(const Writes::Entry& e) const {
  const Write& w = e.job;
  const ProfilePoint& p = profile_.points[w.point];
  const std::uint8_t layout = write_function(profile_.modbus, p);
  Job j;
  j.write = e;
  j.function = write_code_of(profile_.modbus, p);
  if (j.function != layout) j.layout = {j.function, layout};
  if (layout == fc::write_single_coil) {
    j.pdu = {j.function};
    put_be16(j.pdu, p.address);
    put_be16(j.pdu, w.words.at(0) != 0 ? kCoilOn : 0);
  } else if (layout == fc::write_single_register) {
    j.pdu = {j.function};
    put_be16(j.pdu, p.address);
    put_be16(j.pdu, w.words[0]);
  } else {
    j.pdu = {j.function};
    put_be16(j.pdu, p.address);
    put_be16(j.pdu, static_cast<std::uint16_t>(w.words.size()));
    j.pdu.push_back(static_cast<std::uint8_t>(2 * w.words.size()));
    for (const std::uint16_t word : w.words) put_be16(j.pdu, word);
  }
  return j;
}

// A run or reset command's steps on its last step's point are the way into the drive's running
// state (CiA 402's 6, 7 before 15; ABB's 0x047E before 0x047F): written to a drive that runs,
// they would take it out of that state first, coasting or ramping the motor down for a moment.
// While the drive reads as running, only the last of them is written; steps on other points (a
// direction coil before the run coil) are written as they are. A stop is written whole.
void ModbusDriver::skip_the_way_in(Write& w) {
  const std::size_t last = w.points.back();
  std::vector<std::uint16_t> sequence;
  std::vector<std::size_t> points;
  for (std::size_t i = 0; i + 1 < w.sequence.size(); ++i) {
    if (w.points[i] == last) continue;
    sequence.push_back(w.sequence[i]);
    points.push_back(w.points[i]);
  }
  sequence.push_back(w.sequence.back());
  points.push_back(last);
  w.sequence = std::move(sequence);
  w.points = std::move(points);
}

// The slave's echo: FC 05 and 06 repeat the request, FC 16 its address and quantity.
void ModbusDriver::confirm(const Job& j, ByteView pdu) {
  // The echo: address and value (05, 06) or address and quantity (16), after a function code
  // answered_by() accepted.
  const bool took = pdu.size() == 5 && j.pdu.size() >= 5 &&
                    std::equal(pdu.begin() + 1, pdu.end(), j.pdu.begin() + 1);
  if (!took) {
    writes_.settle(*j.write, WriteResult::refused);
    return;
  }
  const Write& w = j.write->job;
  if (w.step + 1 < w.sequence.size()) {
    // A sequence's step the slave took: the register holds it, and the next goes at once, ahead
    // of the polls, unless a newer write to the same point came meanwhile (a stop during a run):
    // that one goes instead, and this command is over, not carried out.
    raw_[w.point] = w.words;
    const bool overtaken =
        std::any_of(writes_.begin(), writes_.end(), [&](const auto& e) { return e.job.meets(w); });
    if (overtaken) {
      writes_.settle(*j.write, WriteResult::no_response);
      return;
    }
    Write next = w;
    ++next.step;
    next.words = {next.sequence[next.step]};
    next.point = next.points[next.step];
    writes_.push_front(std::move(next), j.write->tickets, last_now_ + send_limit());
    return;
  }
  put_in_force(w);
  writes_.settle(*j.write, WriteResult::ok);
}

void ModbusDriver::put_in_force(const Write& w) {
  raw_[w.point] = w.words;
  if (const auto e = exposed_index_[w.point]) {
    values_[*e] = value_of(profile_.points[w.point], w.words);
  }
  switch (w.change) {
    case Change::command:
      // A reset clears a fault the next status read shows; it puts no command in force.
      if (w.command != Command::reset_fault) common_.command = w.command;
      // A stop owed after a trip is paid by any stop the drive took, or ended by a client's run.
      if (w.command != Command::reset_fault) {
        run_in_trip_ = w.asked_in_trip && trip_shown_at_;
        stop_owed_ = false;
        stop_tries_ = 0;
        stop_retry_at_ = {};
      }
      // A run by the set value: the setpoint it wrote is the one in force.
      if (w.runs && w.command == Command::run_forward) common_.setpoint_rpm = w.rpm;
      break;
    case Change::setpoint:
      common_.setpoint_rpm = w.rpm;
      break;
    case Change::point:
      break;
  }
}

// A run that waits while a trip is shown, asked before the trip was, is over, as a newer stop
// overtakes it in apply(). One asked with the trip shown goes after the stop owed.
void ModbusDriver::settle_waiting_runs() {
  writes_.settle_if(
      [](const Writes::Entry& e) {
        return e.job.runs && e.job.change == Change::command &&
               e.job.command == Command::run_forward && !e.job.asked_in_trip;
      },
      WriteResult::no_response);
}

// A stop that waits or is on the line, a client's or the driver's own, is the stop owed: none is
// added. Otherwise the stop goes ahead of what waits, once its back-off allows: a drive that
// refuses it is not asked every cycle, and the first failure is logged (the write has no ticket:
// the log is where a stop that did not land shows).
void ModbusDriver::stop_after_trip() {
  if (on_its_way(Command::stop) || last_now_ < stop_retry_at_) return;
  auto w = write_of(WriteOp::of_command(Command::stop));
  if (!w) return;
  if (stop_tries_ == 1) {
    notices_.emplace_back(
        "the stop owed after a trip was not taken by the drive: written again, "
        "backed off up to the comm timeout, until it is");
  }
  const auto wait =
      std::min<Millis>(poll_interval_ * (1 << std::min(stop_tries_, 10)), timing_.comm_timeout);
  ++stop_tries_;
  stop_retry_at_ = last_now_ + wait;
  writes_.push_front(std::move(*w), {}, last_now_ + send_limit());
}

bool ModbusDriver::on_its_way(Command command) const {
  const auto is = [command](const Write& w) {
    return w.runs && w.change == Change::command && w.command == command;
  };
  if (inflight_ && inflight_->write && is(inflight_->write->job)) return true;
  return std::any_of(writes_.begin(), writes_.end(),
                     [&](const Writes::Entry& e) { return is(e.job); });
}

// The exchange on the line ended without an answer to the write it carried, if any.
void ModbusDriver::fail_inflight() {
  if (inflight_ && inflight_->write) writes_.settle(*inflight_->write, WriteResult::no_response);
  inflight_.reset();
}

}  // namespace drivegate::modbus_device
