// FramedDriver: writes. A command is carried out by the first of its alternatives whose `when`
// holds, with the frame made when it first reaches the line from what is in force then; it is in
// force once the device showed it took it: its reply passing `accept`, or its state passing
// `until`. A setpoint while no run is in force or on its way is stored for the next run (done);
// while one is, the command in force is carried out again at the new setpoint. A point write is
// stored, and sends a frame when one of the point's on_write rules says so. Until a write is in
// force, and when it fails, what was in force stays, and a frame of it that went out is undone
// by the next poll, which carries what is in force (docs/protocols.md, "Writes").
#include <algorithm>
#include <cmath>
#include <variant>

#include "driver.h"

namespace drivegate::framed {
namespace {

WriteStatus status_of(WriteCheck c) {
  return c == WriteCheck::invalid_value ? WriteStatus::invalid_value : WriteStatus::refused;
}

// Action status values (Point::status).
enum class ActionStatus : std::uint8_t { idle = 0, pending = 1, done = 2, no_response = 3 };

}  // namespace

const Alternative* FramedDriver::alternative(Command c, const std::vector<Val>& vars) const {
  const auto it = d_->commands.find(c);
  if (it == d_->commands.end()) return nullptr;
  const Scope s{vars, {}, {}};
  for (const Alternative& a : it->second) {
    if (!a.when || a.when->holds(s)) return &a;
  }
  return nullptr;
}

std::optional<std::size_t> FramedDriver::on_write_rule(std::size_t point, double value) const {
  const Point& p = d_->points[point];
  std::vector<Val> vars = state_.vars();
  vars[builtin::value] = Val::of(value);
  const Scope s{vars, {}, {}};
  for (std::size_t i = 0; i < p.on_write.size(); ++i) {
    if (!p.on_write[i].when || p.on_write[i].when->holds(s)) return i;
  }
  return std::nullopt;
}

// One part against `vars` (what is in force, or what the parts before it leave), which it then
// changes as the part would.
FramedDriver::Judged FramedDriver::judge(const WriteOp& op, std::vector<Val>& vars) const {
  const auto readiness = [&]() {
    return !ready() && !d_->timing.writes_wait_for_ready ? WriteCheck::refused : WriteCheck::ok;
  };
  switch (op.target) {
    case WriteOp::Target::forward:  // only ever handed to a driver that forwards()
      return {WriteCheck::invalid_value, nullptr};
    case WriteOp::Target::command: {
      std::vector<Val> proposed = vars;
      proposed[builtin::command] = Val::of(static_cast<double>(op.command));
      const Alternative* a = alternative(op.command, proposed);
      if (a == nullptr) return {WriteCheck::invalid_value, nullptr};
      const Scope s{proposed, {}, {}};
      if (a->invalid && a->invalid->holds(s)) return {WriteCheck::invalid_value, a};
      if (a->refuse && a->refuse->holds(s)) return {WriteCheck::refused, a};
      if (const WriteCheck r = readiness(); r != WriteCheck::ok) return {r, a};
      if (a->becomes) vars[builtin::command] = Val::of(static_cast<double>(*a->becomes));
      return {WriteCheck::ok, a};
    }
    case WriteOp::Target::setpoint: {
      if (!d_->setpoint) return {WriteCheck::invalid_value, nullptr};
      const Setpoint& sp = *d_->setpoint;
      if (sp.limited && (op.rpm < sp.min || op.rpm > sp.max)) {
        return {WriteCheck::invalid_value, nullptr};
      }
      std::vector<Val> proposed = vars;
      proposed[builtin::setpoint] = Val::of(op.rpm);
      const Scope s{proposed, {}, {}};
      if (sp.invalid && sp.invalid->holds(s)) return {WriteCheck::invalid_value, nullptr};
      if (sp.refuse && sp.refuse->holds(s)) return {WriteCheck::refused, nullptr};
      vars = std::move(proposed);
      return {WriteCheck::ok, nullptr};
    }
    case WriteOp::Target::point:
      break;
  }
  if (op.point >= d_->points.size()) return {WriteCheck::invalid_value, nullptr};
  const Point& p = d_->points[op.point];
  const bool writable =
      p.spec.table == drivegate::Table::holding || p.spec.table == drivegate::Table::coil;
  if (!writable || std::holds_alternative<std::monostate>(op.value) ||
      std::holds_alternative<std::string>(op.value)) {
    return {WriteCheck::invalid_value, nullptr};
  }
  vars[p.var] = Val::of(as_double(op.value));
  return {WriteCheck::ok, nullptr};
}

WriteCheck FramedDriver::check(std::span<const WriteOp> request) const {
  std::vector<Val> vars = state_.vars();
  for (const WriteOp& op : request) {
    if (const Judged j = judge(op, vars); j.verdict != WriteCheck::ok) return j.verdict;
  }
  return WriteCheck::ok;
}

bool FramedDriver::run_on_its_way() const {
  return std::any_of(writes_.begin(), writes_.end(), [](const Writes::Entry& e) {
    return e.job.kind == Job::Kind::command && is_run(e.job.command);
  });
}

WriteStatus FramedDriver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  writes_.expire(now);
  std::vector<Val> vars = state_.vars();
  const Judged j = judge(op, vars);
  if (j.verdict != WriteCheck::ok) return status_of(j.verdict);
  const TimePoint deadline = now + confirm_;
  Job job;
  switch (op.target) {
    case WriteOp::Target::setpoint: {
      job.kind = Job::Kind::setpoint;
      job.rpm = op.rpm;
      // No run in force and none on its way: stored, the next run carries it.
      if (!is_run(static_cast<Command>(state_.num(builtin::command))) && !run_on_its_way()) {
        state_.set(builtin::setpoint, op.rpm);
        publish();
        return WriteStatus::done;
      }
      break;
    }
    case WriteOp::Target::command: {
      job.kind = Job::Kind::command;
      job.command = op.command;
      if (!j.alt->send) {  // nothing to send: in force at once
        job.alt = j.alt;
        put_in_force(job);
        publish();
        return WriteStatus::done;
      }
      // A command decides what the line carries: the commands and setpoints still waiting for the
      // line, or waiting for the device's state to show them, are overtaken by it (0x0B), so a
      // motor is not started only to be stopped.
      writes_.settle_if(
          [](const Writes::Entry& e) {
            const bool motion = e.job.kind != Job::Kind::point;
            return motion && (!e.sent || e.job.awaiting_state);
          },
          WriteResult::no_response);
      break;
    }
    case WriteOp::Target::point: {
      job.kind = Job::Kind::point;
      job.point = op.point;
      job.value = as_double(op.value);
      const Point& p = d_->points[op.point];
      state_.set(p.var, job.value);
      job.rule = on_write_rule(op.point, job.value);
      if (!job.rule || !p.on_write[*job.rule].send) {
        publish();
        return WriteStatus::done;
      }
      if (p.status)
        state_.set(d_->points[*p.status].var, static_cast<double>(ActionStatus::pending));
      publish();
      break;
    }
    case WriteOp::Target::forward:
      return WriteStatus::invalid_value;
  }
  writes_.push(job, t, deadline);
  return WriteStatus::pending;
}

// What is in force once the write is: the state `vars` would hold.
void FramedDriver::propose(const Job& j, std::vector<Val>& vars) const {
  switch (j.kind) {
    case Job::Kind::command:
      if (j.alt != nullptr && j.alt->becomes) {
        vars[builtin::command] = Val::of(static_cast<double>(*j.alt->becomes));
      } else {
        vars[builtin::command] = Val::of(static_cast<double>(j.command));
      }
      break;
    case Job::Kind::setpoint:
      vars[builtin::setpoint] = Val::of(j.rpm);
      break;
    case Job::Kind::point:
      vars[d_->points[j.point].var] = Val::of(j.value);
      break;
  }
}

void FramedDriver::put_in_force(const Job& j) {
  switch (j.kind) {
    case Job::Kind::command:
      if (j.alt != nullptr && j.alt->becomes) {
        state_.set(builtin::command, static_cast<double>(*j.alt->becomes));
      }
      break;
    case Job::Kind::setpoint:
      state_.set(builtin::setpoint, j.rpm);
      break;
    case Job::Kind::point:
      break;  // stored when written
  }
}

// The frame of the first write waiting for the line, made from what is in force now.
std::optional<Exchange> FramedDriver::next_write(TimePoint now) {
  while (!writes_.empty()) {
    Writes::Entry& e = writes_.front();
    if (e.sent) return std::nullopt;  // on the line, or waiting for the state to show it
    Job& job = e.job;
    std::vector<Val> vars = state_.vars();
    switch (job.kind) {
      case Job::Kind::command:
        vars[builtin::command] = Val::of(static_cast<double>(job.command));
        job.alt = alternative(job.command, vars);
        break;
      case Job::Kind::setpoint: {
        const auto in_force = static_cast<Command>(state_.num(builtin::command));
        if (!is_run(in_force)) {
          // The run it was for is no longer in force (a stop or a fault came first): stored.
          state_.set(builtin::setpoint, job.rpm);
          writes_.settle_front(WriteResult::ok);
          publish();
          continue;
        }
        vars[builtin::setpoint] = Val::of(job.rpm);
        job.alt = alternative(in_force, vars);
        break;
      }
      case Job::Kind::point: {
        const Point::OnWrite& w = d_->points[job.point].on_write[*job.rule];
        vars[builtin::value] = Val::of(job.value);
        job.message = w.send;
        break;
      }
    }
    if (job.kind != Job::Kind::point) {
      if (job.alt == nullptr || !job.alt->send) {
        // What is in force changed since it was judged: it cannot be carried out now.
        writes_.settle_front(WriteResult::refused);
        continue;
      }
      job.message = job.alt->send;
      const Setpoint* sp = d_->setpoint ? &*d_->setpoint : nullptr;
      job.awaiting_state =
          job.kind == Job::Kind::setpoint && sp != nullptr && (sp->until || sp->accept)
              ? sp->until.has_value()
              : job.alt->until.has_value();
    }
    e.sent = true;
    return exchange(*job.message, vars, Sent::write, now, e.deadline);
  }
  return std::nullopt;
}

// The reply to the write on the line.
void FramedDriver::on_reply_to_write(const Frame& f) {
  (void)f;
  if (!writes_.front_on_line()) return;
  Writes::Entry& e = writes_.front();
  const Job& job = e.job;
  const Scope s = state_.scope_with(fields_, sent_);
  const Expr* accept = nullptr;
  if (job.kind == Job::Kind::point) {
    const auto& w = d_->points[job.point].on_write[*job.rule];
    if (w.accept) accept = &*w.accept;
  } else if (job.kind == Job::Kind::setpoint && d_->setpoint && d_->setpoint->accept) {
    accept = &*d_->setpoint->accept;
  } else if (job.alt != nullptr && job.alt->accept) {
    accept = &*job.alt->accept;
  }
  if (accept != nullptr && !accept->holds(s)) {
    writes_.settle_front(WriteResult::refused);
    return;
  }
  if (job.awaiting_state) return;  // the reply says it arrived; the state will say it took it
  put_in_force(job);
  writes_.settle_front(WriteResult::ok);
}

// A write sent and waiting for the device's state: in force once `until` holds, refused when
// `refuse_on` does.
void FramedDriver::confirm_by_state() {
  if (!writes_.front_on_line() || !writes_.front().job.awaiting_state) return;
  const Job& job = writes_.front().job;
  const Expr* until = nullptr;
  const Expr* refuse_on = nullptr;
  if (job.kind == Job::Kind::setpoint && d_->setpoint && d_->setpoint->until) {
    until = &*d_->setpoint->until;
    if (d_->setpoint->refuse_on) refuse_on = &*d_->setpoint->refuse_on;
  } else if (job.alt != nullptr) {
    if (job.alt->until) until = &*job.alt->until;
    if (job.alt->refuse_on) refuse_on = &*job.alt->refuse_on;
  }
  std::vector<Val> vars = state_.vars();
  propose(job, vars);
  const Scope s{vars, {}, {}};
  if (until != nullptr && until->holds(s)) {
    put_in_force(job);
    writes_.settle_front(WriteResult::ok);
    return;
  }
  if (refuse_on != nullptr && refuse_on->holds(s)) writes_.settle_front(WriteResult::refused);
}

void FramedDriver::settled(const Writes::Entry& e, WriteResult r) {
  const Job& job = e.job;
  if (job.kind == Job::Kind::point) {
    const Point& p = d_->points[job.point];
    if (p.status) {
      const auto s = r == WriteResult::ok ? ActionStatus::done : ActionStatus::no_response;
      state_.set(d_->points[*p.status].var, static_cast<double>(s));
    }
  }
  // The device may have acted on a frame of a write that failed: the next poll tells it what is
  // in force, at once.
  if (e.sent && r != WriteResult::ok) poll_now_ = true;
  publish();
}

}  // namespace drivegate::framed
