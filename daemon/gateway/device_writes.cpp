// Writes at one device. A request is validated against the register map, judged whole by the
// driver (Driver::check), and only then applied, one part at a time, each part once the one
// before it settled. So a request the drive cannot take changes nothing, and when the line fails
// a later part after an earlier one took effect, the client gets the failure and the register
// image shows what the drive really holds.
//
// Requests wait in a short queue (kMaxQueuedWrites; past it busy at once) and are carried out
// oldest first, one part at a time. A part goes to the driver at once when the device owes no
// poll; after a write, if a poll of its own is due, the next part waits for a write turn, which
// the bus engine alternates with the line's polls: however many clients write, every device, the
// written one included, keeps being polled. A request equal
// to the one still queued before it is answered with it. A stop (a client's, the failsafe's,
// shutdown's) does not queue: it goes to the driver at once, and the queued requests that would
// run the motor after it are dropped, never sent (no_response).
#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <optional>

#include "gateway/device.h"
#include "gateway/forward_access.h"
#include "gateway/value_codec.h"

namespace drivegate {

namespace {

// Why a write to a device a reload waits to replace is refused (Device::hold_for_reload).
constexpr const char* kHeldForReload = "a reload is replacing the device: try again";

Outcome to_outcome(WriteCheck c) {
  return c == WriteCheck::invalid_value ? Outcome::invalid_value : Outcome::refused;
}

Outcome to_outcome(WriteResult r) {
  switch (r) {
    case WriteResult::ok:
      return Outcome::ok;
    case WriteResult::refused:
      return Outcome::refused;
    case WriteResult::no_response:
      return Outcome::no_response;
  }
  return Outcome::refused;
}

CommonWrite write_kind(const MappedPoint& p) {
  const CommonRow* row = p.row();
  return row != nullptr ? row->write : CommonWrite::none;
}

std::int64_t whole(const Value& v) {
  return static_cast<std::int64_t>(as_double(v));
}

// The command a command part carries (validate() kept the value within the command names).
Command command_of(const Value& v) {
  return command_from_value(static_cast<std::uint16_t>(whole(v))).value_or(Command::stop);
}

// What the driver is asked for a validated part; nothing for the heartbeat, the gateway's own.
std::optional<WriteOp> op_of(const MappedPoint& point, const Value& value) {
  switch (write_kind(point)) {
    case CommonWrite::heartbeat:
      return std::nullopt;
    case CommonWrite::command:
      return WriteOp::of_command(command_of(value));
    case CommonWrite::setpoint:
      return WriteOp::of_setpoint(static_cast<std::int32_t>(whole(value)));
    case CommonWrite::none:
      break;
  }
  return WriteOp::of_point(point.index, value);
}

template <class Parts>
bool commands(const Parts& parts, bool (*which)(Command)) {
  return std::any_of(parts.begin(), parts.end(), [which](const auto& p) {
    return write_kind(*p.point) == CommonWrite::command && which(command_of(p.value));
  });
}

bool is_stop(Command c) {
  return c == Command::stop || c == Command::quick_stop;
}

// Why the drive refused a run, for the audit trail and the log: the fault it reports, if it
// reports one (a tripped drive does not run until reset_fault); empty when it reports none.
std::string why_run_refused(const CommonState& s) {
  if (s.faults.empty()) return {};
  char native[16];
  std::snprintf(native, sizeof native, "0x%X", static_cast<unsigned>(s.native_fault));
  return "the drive reports a fault: " + std::string(to_string(most_severe(s.faults))) +
         " (native " + native + "); it runs again after reset_fault";
}

// Whether a number can be written at all: NaN and the infinities never reach a drive.
bool finite(const Value& v) {
  const auto* d = std::get_if<double>(&v);
  return d == nullptr || std::isfinite(*d);
}

}  // namespace

AccessLevel required_level(const MappedPoint& p) {
  const bool operates =
      write_kind(p) != CommonWrite::none || p.spec.write_level == PointSpec::WriteLevel::operate;
  return operates ? AccessLevel::operate : AccessLevel::maintain;
}

Outcome Device::write(const Session& session, Table table, std::uint16_t address,
                      std::span<const std::uint16_t> in, WriteDone done, TimePoint now) {
  Answer a = answer_to(session, std::move(done), describe_registers(table, address, in), now);
  return answered(a, submit(session, table, address, in, a, now, Origin::plc), now);
}

void Device::command(Command c, WriteDone done, TimePoint now, SourceKind source) {
  const auto value = static_cast<std::uint16_t>(c);
  const Session session = gateway_session(source);
  Answer a = answer_to(session, done, "command=" + std::string(to_string(c)), now);
  const Outcome at_once =
      answered(a,
               submit(session, Table::holding, 0, std::span<const std::uint16_t>(&value, 1), a, now,
                      Origin::gateway),
               now);
  if (at_once != Outcome::ok) done(at_once);
}

Outcome Device::validate(const Session& session, Table table, std::uint16_t address,
                         std::span<const std::uint16_t> in, std::vector<Part>& parts) const {
  const bool bits = table == Table::coil;
  std::size_t i = 0;
  while (i < in.size()) {
    const auto at = static_cast<std::uint16_t>(address + i);
    const MappedPoint* p = map_.at(table, at);
    // A write must start at a point and cover all its registers.
    if (p == nullptr || p->address != at) return Outcome::no_such_point;
    const std::size_t count = bits ? 1 : p->spec.register_count();
    if (i + count > in.size()) return Outcome::no_such_point;
    if (p->spec.access() != Access::read_write) return Outcome::no_such_point;
    // outcome.h: beyond the session's level is denied, and the only reason for it.
    if (required_level(*p) > session.access) return Outcome::denied;
    Value v;
    if (bits) {
      v = std::int64_t{in[i] != 0 ? 1 : 0};
    } else {
      std::array<std::uint16_t, 4> swapped{};
      auto words = in.subspan(i, count);
      if (session.word_order == WordOrder::little && has_word_order(p->spec)) {
        std::reverse_copy(words.begin(), words.end(), swapped.begin());
        words = std::span(swapped).first(count);
      }
      // A float register holding NaN or an infinity does not decode: invalid.
      auto decoded = decode_value(p->spec, words);
      if (!decoded || !finite(*decoded)) return Outcome::invalid_value;
      v = std::move(*decoded);
      const double x = as_double(v);
      if ((p->spec.min != 0.0 || p->spec.max != 0.0) && (x < p->spec.min || x > p->spec.max)) {
        return Outcome::invalid_value;
      }
    }
    parts.push_back({p, std::move(v)});
    i += count;
  }
  return Outcome::ok;
}

Outcome Device::submit(const Session& session, Table table, std::uint16_t address,
                       std::span<const std::uint16_t> in, Answer& answer, TimePoint now,
                       Origin origin) {
  std::vector<Part> parts;
  if (const Outcome o = validate(session, table, address, in, parts); o != Outcome::ok) {
    return o;
  }
  return enqueue(session, std::move(parts), answer, now, origin);
}

Outcome Device::write_points(const Session& session, std::span<const PointWrite> points,
                             WriteDone done, TimePoint now) {
  std::string asked;
  for (const PointWrite& w : points) {
    if (!asked.empty()) asked += ' ';
    asked += w.point->spec.name + "=" + value_text(w.point->spec, w.value);
  }
  Answer a = answer_to(session, std::move(done), std::move(asked), now);
  return answered(a, write_points_checked(session, points, a, now), now);
}

Outcome Device::write_points_checked(const Session& session, std::span<const PointWrite> points,
                                     Answer& answer, TimePoint now) {
  Session in_map_order = session;
  in_map_order.word_order = WordOrder::big;  // encode_value's order
  std::vector<Part> parts;
  for (const PointWrite& w : points) {
    const PointSpec& spec = w.point->spec;
    const bool bits = spec.table == Table::coil;
    std::array<std::uint16_t, 4> regs{};
    const std::size_t count = bits ? 1 : spec.register_count();
    // Strings are not writable.
    if (spec.type == PointType::string || count > regs.size()) return Outcome::no_such_point;
    // NaN would encode as 0 (and compare unequal to everything below): refused before that.
    if (!finite(w.value)) return Outcome::invalid_value;
    const auto words = std::span(regs).first(count);
    if (bits) {
      const double x = as_double(w.value);
      if (x != 0.0 && x != 1.0) return Outcome::invalid_value;
      regs[0] = x != 0.0 ? 1 : 0;
    } else {
      encode_value(spec, w.value, words);
      // encode_value saturates and rounds: what the registers hold must be what was asked (a
      // value between two steps of the point's scale is refused, not rounded; only the error
      // of binary floating point is let through).
      const auto held = decode_value(spec, words);
      const double asked = as_double(w.value);
      const double step = spec.scale == 0.0 ? 1.0 : spec.scale;
      const double tolerance = spec.type == PointType::f32
                                   ? std::max(1e-6 * std::fabs(asked), 1e-30)
                               : spec.type == PointType::f64 ? 0.0
                                                             : 1e-6 * std::fabs(step);
      if (!held || !(std::fabs(as_double(*held) - asked) <= tolerance)) {
        return Outcome::invalid_value;
      }
    }
    std::vector<Part> one;
    if (const Outcome o = validate(in_map_order, spec.table, w.point->address, words, one);
        o != Outcome::ok) {
      return o;
    }
    parts.insert(parts.end(), one.begin(), one.end());
  }
  if (parts.empty()) return Outcome::invalid_value;
  return enqueue(session, std::move(parts), answer, now, Origin::plc);
}

// docs/safety.md, "Command authority": while the failsafe is latched, only a run from a source
// that feeds it (the PLC) clears it; a run from anywhere else is refused before it is applied.
Outcome Device::refuse_run_while_latched(const char* source, TimePoint now) {
  ++write_stats_.refused_failsafe;
  if (const auto held = refusal_log_.admit(now)) {
    log_->warn(
        "device {}: run from {} refused: the failsafe is latched, and only a run from the "
        "PLC clears it{}",
        config_.name, source, net::held_note(*held));
  }
  return Outcome::refused;
}

Outcome Device::enqueue(const Session& session, std::vector<Part> parts, Answer& answer,
                        TimePoint now, Origin origin) {
  const bool feeds = origin == Origin::plc && session.feeds_failsafe;
  if (closed_to_clients_ && origin == Origin::plc) {
    answer.record.why = "shutting down";
    return Outcome::no_response;
  }
  // A client decides from now on.
  if (origin == Origin::plc && start_ == StartCheck::stop_due) start_ = StartCheck::checked;
  // One request writing setpoint and command together means "run at this speed": the setpoint
  // applies first, whatever the address order.
  std::stable_partition(parts.begin(), parts.end(),
                        [](const Part& p) { return write_kind(*p.point) != CommonWrite::command; });
  answer.record.points = describe(parts);  // in the order they are applied
  // A drive that stopped answering cannot take anything: say so now rather than after a
  // timeout. The heartbeat alone is the gateway's and always succeeds.
  const bool heartbeat_only =
      parts.size() == 1 && write_kind(*parts[0].point) == CommonWrite::heartbeat;
  if (heartbeat_only) answer.audit = Answer::Audit::count;
  if (comm_lost() && !heartbeat_only) return Outcome::no_response;
  if (held_for_reload_ && origin == Origin::plc && !heartbeat_only && !commands(parts, &is_stop)) {
    answer.record.why = kHeldForReload;
    return Outcome::busy;
  }
  if (failsafe_.latched() && !feeds && commands(parts, &is_run)) {
    answer.record.why = "the failsafe is latched";
    return refuse_run_while_latched(
        origin == Origin::plc ? "a client that does not feed it" : "the gateway", now);
  }

  // The driver judges the whole request before any part of it is applied.
  std::vector<WriteOp> ops;
  for (const Part& p : parts) {
    if (auto op = op_of(*p.point, p.value)) ops.push_back(std::move(*op));
  }
  if (!ops.empty()) {
    if (const WriteCheck c = driver_->check(ops); c != WriteCheck::ok) {
      if (c == WriteCheck::refused && commands(parts, &is_run)) {
        answer.record.why = why_run_refused(driver_->common());
      }
      return to_outcome(c);
    }
  }

  // A stop goes ahead of everything; a request that also runs the motor is no stop, and waits its
  // turn like any run (else it would drop the runs queued before it and then run itself).
  const bool urgent =
      origin == Origin::gateway || (commands(parts, &is_stop) && !commands(parts, &is_run));
  if (!urgent && !heartbeat_only) {
    // Equal to the request queued last, which has not started: the same effect, one answer.
    // Asked with the same fault in view (a run from a client that read a trip is not the run of
    // one that did not: WriteOp::fault_seen).
    Request* last = writes_.last_queued();
    if (last != nullptr && last->feeds_failsafe == feeds && !last->answers.empty() &&
        last->answers.front().fault_seen == answer.fault_seen &&
        std::equal(parts.begin(), parts.end(), last->parts.begin(), last->parts.end(),
                   [](const Part& a, const Part& b) {
                     return a.point == b.point && a.value == b.value;
                   })) {
      ++write_stats_.coalesced;
      answer.taken = true;
      last->answers.push_back(std::move(answer));
      return Outcome::ok;
    }
  }
  if (!heartbeat_only && writes_.full(urgent)) {
    ++write_stats_.busy;
    return Outcome::busy;
  }
  if (urgent) supersede_runs(now);

  auto owned = std::make_unique<Request>();
  owned->parts = std::move(parts);
  owned->urgent = urgent;
  owned->feeds_failsafe = feeds;
  answer.taken = true;
  owned->answers.push_back(std::move(answer));
  Request& r = writes_.push(std::move(owned), now);
  // A stop and the heartbeat go to the driver (or the image) at once.
  return begin(r, urgent || heartbeat_only, now);
}

// A request just queued: started now when it must be (`at_once`) or may be (it heads the queue
// and no poll of the device's own is due), else left for a write turn.
Outcome Device::begin(Request& r, bool at_once, TimePoint now) {
  if (!at_once && (writes_.head() != &r || !may_release(now))) {
    if (kick_) kick_();  // the engine gives it a write turn
    return Outcome::ok;
  }
  Outcome failure = Outcome::ok;
  const Progress progress = advance(r, now, failure);
  if (progress == Progress::failed) {  // answered by the return value instead (yet recorded)
    for (Answer& a : r.answers) a.done = nullptr;
    r.forward_done = nullptr;
  }
  if (progress != Progress::waiting) finish(&r, failure, now);
  publish(now);
  if (progress == Progress::waiting && kick_) kick_();
  return failure;
}

// A stop is on its way: the queued requests that would run the motor after it never reach it.
void Device::supersede_runs(TimePoint now) {
  std::vector<const Request*> dropped;
  for (const auto& r : writes_.requests()) {
    if (!r->urgent && !r->started() && commands(r->parts, &is_run)) dropped.push_back(r.get());
  }
  for (const Request* r : dropped) finish(r, Outcome::no_response, now, "a stop went before it");
}

PendingWrites Device::pending_writes(TimePoint now) const {
  return writes_.pending(driver_->wake_at() <= now);
}

// A queued write's part may go to the driver outside a write turn unless the device's last
// exchange carried a write and a poll of its own is now due: then that poll goes first.
bool Device::may_release(TimePoint now) const {
  return writes_.may_release(driver_->wake_at() <= now);
}

// The head request's next parts go to the driver, up to the first one that needs the line;
// requests that finish without it (a setpoint stored while stopped) make way for the next at
// once. Outside a write turn only while the device owes no poll.
bool Device::release(TimePoint now, bool write_turn) {
  bool applied = false;
  while (Request* r = writes_.head()) {
    if (r->carried() || (!write_turn && !may_release(now))) break;
    Outcome failure = Outcome::ok;
    const Progress progress = advance(*r, now, failure);
    applied = true;
    if (progress == Progress::waiting) break;
    finish(r, failure, now);
  }
  return applied;
}

// Applies parts from r.next on until one is pending or fails.
Device::Progress Device::advance(Request& r, TimePoint now, Outcome& failure) {
  if (r.forward) return advance_forward(r, now, failure);
  while (r.next < r.parts.size()) {
    const Part& part = r.parts[r.next++];
    std::optional<WriteOp> maybe_op = op_of(*part.point, part.value);
    if (!maybe_op) {
      heartbeat_ = static_cast<std::uint16_t>(whole(part.value));
      image_.stale();
      continue;
    }
    WriteOp& op = *maybe_op;
    if (!r.answers.empty()) op.fault_seen = r.answers.front().fault_seen;
    const bool run = op.target == WriteOp::Target::command && is_run(op.command);
    // The failsafe may have latched while the request waited.
    if (run && failsafe_.latched() && !r.feeds_failsafe) {
      for (Answer& a : r.answers) a.record.why = "the failsafe is latched";
      failure = refuse_run_while_latched("a client that does not feed it", now);
      return Progress::failed;
    }
    const Ticket t = writes_.ticket();
    const WriteStatus s = driver_->apply(op, t, now);
    image_.stale();
    const bool taken = s == WriteStatus::done || s == WriteStatus::pending;
    if (taken && r.feeds_failsafe && run && failsafe_.reset(now)) {
      log_->info("device {}: failsafe reset by {} from Modbus", config_.name,
                 to_string(op.command));
    }
    switch (s) {
      case WriteStatus::done:
        continue;
      case WriteStatus::pending: {
        // Due by the driver's whole write_timeout from now (WriteQueue::handed).
        [[maybe_unused]] const bool handed = writes_.handed(r, t, now);
        assert(handed);  // advance() is never called on a request whose part is carried
        return Progress::waiting;
      }
      case WriteStatus::invalid_value:
        failure = Outcome::invalid_value;
        return Progress::failed;
      case WriteStatus::refused:
        if (run) {
          for (Answer& a : r.answers) a.record.why = why_run_refused(driver_->common());
        }
        failure = Outcome::refused;
        return Progress::failed;
    }
  }
  return Progress::done;
}

// A forwarded request is one part: handed to the driver once, then waiting for the slave.
Device::Progress Device::advance_forward(Request& r, TimePoint now, Outcome& failure) {
  if (r.started()) return Progress::done;
  ++r.next;
  const Ticket t = writes_.ticket();
  switch (driver_->apply(WriteOp::of_forward(*r.forward), t, now)) {
    case WriteStatus::pending: {
      [[maybe_unused]] const bool handed = writes_.handed(r, t, now);
      assert(handed);
      return Progress::waiting;
    }
    case WriteStatus::done:  // a forward always needs the line: nothing came back to answer
    case WriteStatus::refused:
      failure = Outcome::refused;
      return Progress::failed;
    case WriteStatus::invalid_value:
      failure = Outcome::invalid_value;
      return Progress::failed;
  }
  failure = Outcome::refused;
  return Progress::failed;
}

Outcome Device::forward(const Session& session, std::span<const std::uint8_t> pdu, ForwardDone done,
                        TimePoint now) {
  const ForwardVerdict verdict = judge_forward(pdu, static_cast<std::uint8_t>(config_.address));
  // A forwarded read is not a write: recorded only when it is refused for what it is. A
  // forwarded write is audited like any other.
  const bool reads_only = verdict.needs == AccessLevel::read;
  Answer a = answer_to(session, nullptr, describe_pdu(pdu), now);
  if (reads_only && verdict.refusal == Outcome::ok) a.audit = Answer::Audit::none;
  const Outcome o = [&] {
    if (!driver_->forwards()) return Outcome::no_such_point;
    // outcome.h: beyond the session's level is denied, checked before anything else; a function
    // no level may send is beyond every session's.
    if (verdict.refusal == Outcome::denied) {
      a.record.why = verdict.why;
      return Outcome::denied;
    }
    if (verdict.needs > session.access) return Outcome::denied;
    if (verdict.refusal != Outcome::ok) {
      a.record.why = verdict.why;
      return verdict.refusal;
    }
    if (closed_to_clients_ || comm_lost()) return Outcome::no_response;
    if (held_for_reload_) {
      a.record.why = kHeldForReload;
      return Outcome::busy;
    }
    // Reads wait in places of their own: however many read clients fill theirs, a write from
    // a client that may write is never refused busy for them.
    if (writes_.full(false, reads_only)) {
      ++write_stats_.busy;
      return Outcome::busy;
    }
    auto owned = std::make_unique<Request>();
    owned->forward = Bytes(pdu.begin(), pdu.end());
    owned->forward_done = std::move(done);
    owned->reads_only = reads_only;
    owned->feeds_failsafe = false;
    a.taken = true;
    owned->answers.push_back(std::move(a));
    return begin(writes_.push(std::move(owned), now), false, now);
  }();
  return answered(a, o, now);
}

void Device::settle(const Completion& c, TimePoint now) {
  Request* r = writes_.carrying(c.ticket);
  if (r == nullptr) return;  // its request timed out already
  if (r->forward) r->reply = c.reply;
  if (c.result != WriteResult::ok || r->all_applied()) {
    // Done, or failed: the parts after it are never applied. The next request may go.
    finish(r, to_outcome(c.result), now);
    next_request(now);
    return;
  }
  [[maybe_unused]] const bool confirmed = writes_.confirmed(*r, now);
  assert(confirmed);  // carrying() found it carried
  if (!r->urgent) {
    // The next part goes now, or at the device's next write turn if a poll is due first.
    release(now, false);
    if (kick_) kick_();
    return;
  }
  Outcome failure = Outcome::ok;
  const Progress progress = advance(*r, now, failure);
  if (progress != Progress::waiting) finish(r, failure, now);
  if (progress == Progress::waiting && kick_) kick_();
}

void Device::finish(const Request* r, Outcome outcome, TimePoint now, std::string_view why) {
  const std::unique_ptr<Request> owned = writes_.remove(r);
  if (owned == nullptr) return;
  // Only a write that succeeded proves the PLC is there: one refused for any reason (by the
  // gateway or by the drive) or unanswered feeds nothing (docs/safety.md).
  if (outcome == Outcome::ok && owned->feeds_failsafe &&
      std::any_of(owned->parts.begin(), owned->parts.end(),
                  [](const Part& p) { return write_kind(*p.point) != CommonWrite::none; })) {
    failsafe_.fed(now);
  }
  // A forwarded request the slave answered with an exception is relayed as it came (ok to the
  // client, which reads the exception), but the audit trail says the slave refused it.
  Outcome recorded = outcome;
  std::string reason(why);
  if (owned->forward && outcome == Outcome::ok && owned->reply.size() >= 2 &&
      (owned->reply[0] & 0x80) != 0) {
    recorded = Outcome::refused;
    reason = "exception " + std::to_string(owned->reply[1]) + " from the slave";
  }
  for (Answer& a : owned->answers) {
    if (!reason.empty()) a.record.why = reason;
    record(a, recorded, now);
    if (a.done) a.done(outcome);
  }
  if (owned->forward_done) owned->forward_done(outcome, owned->reply);
}

// Requests not settled by their deadline: no_response. One still queued is never applied after
// it.
void Device::expire_requests(TimePoint now) {
  std::vector<const Request*> late;
  for (const auto& r : writes_.requests()) {
    if (now >= r->deadline) late.push_back(r.get());
  }
  for (const Request* r : late) {
    finish(r, Outcome::no_response, now,
           r->started() ? "the drive did not confirm it in time" : "not sent before its deadline");
  }
  if (!late.empty()) next_request(now);
}

// A request left the queue: the next one's first part goes now, or at a write turn.
void Device::next_request(TimePoint now) {
  if (writes_.head() == nullptr) return;
  release(now, false);
  if (kick_) kick_();
}

void Device::fail_pending(Outcome why, TimePoint now, std::string_view reason) {
  auto failing = writes_.take_all();
  for (auto& r : failing) {
    for (Answer& a : r->answers) {
      if (!reason.empty()) a.record.why = reason;
      record(a, why, now);
      if (a.done) a.done(why);
    }
    if (r->forward_done) r->forward_done(why, {});
  }
}

}  // namespace drivegate
