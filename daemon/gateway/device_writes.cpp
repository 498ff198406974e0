// Modbus writes at one device. A request is validated against the register map, judged whole by
// the driver (Driver::check), and only then applied, one part at a time, each part once the one
// before it settled. So a request the drive cannot take changes nothing, and when the line fails
// a later part after an earlier one took effect, the PLC gets the failure and the register image
// shows what the drive really holds.
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "gateway/device.h"
#include "gateway/device_request.h"
#include "gateway/value_codec.h"

namespace drivegate {

using modbus::Exception;

namespace {

Exception to_exception(WriteCheck c) {
  return c == WriteCheck::invalid_value ? Exception::illegal_data_value
                                        : Exception::server_device_failure;
}

Exception to_exception(WriteResult r) {
  switch (r) {
    case WriteResult::ok:
      return Exception::none;
    case WriteResult::refused:
      return Exception::server_device_failure;
    case WriteResult::no_response:
      return Exception::gateway_target_failed;
  }
  return Exception::server_device_failure;
}

CommonWrite write_kind(const MappedPoint& p) {
  const CommonRow* row = p.row();
  return row != nullptr ? row->write : CommonWrite::none;
}

std::int64_t whole(const Value& v) {
  return static_cast<std::int64_t>(as_double(v));
}

// What the driver is asked for a validated part; nothing for the heartbeat, the gateway's own.
std::optional<WriteOp> op_of(const MappedPoint& point, const Value& value) {
  switch (write_kind(point)) {
    case CommonWrite::heartbeat:
      return std::nullopt;
    case CommonWrite::command:
      // validate() kept the value within the command names.
      return WriteOp::of_command(
          command_from_value(static_cast<std::uint16_t>(whole(value))).value_or(Command::stop));
    case CommonWrite::setpoint:
      return WriteOp::of_setpoint(static_cast<std::int32_t>(whole(value)));
    case CommonWrite::none:
      break;
  }
  return WriteOp::of_point(point.index, value);
}

}  // namespace

modbus::AccessLevel required_level(const MappedPoint& p) {
  return write_kind(p) != CommonWrite::none ? modbus::AccessLevel::operate
                                            : modbus::AccessLevel::maintain;
}

Exception Device::write(const modbus::Session& session, Table table, std::uint16_t address,
                        std::span<const std::uint16_t> in, modbus::WriteDone done, TimePoint now) {
  return submit(session, table, address, in, std::move(done), now, Origin::plc);
}

void Device::command(Command c, modbus::WriteDone done, TimePoint now) {
  const auto value = static_cast<std::uint16_t>(c);
  const Exception e = submit(kGatewaySession, Table::holding, 0,
                             std::span<const std::uint16_t>(&value, 1), done, now, Origin::gateway);
  if (e != Exception::none) done(e);
}

Exception Device::validate(const modbus::Session& session, Table table, std::uint16_t address,
                           std::span<const std::uint16_t> in, std::vector<Part>& parts) const {
  const bool bits = table == Table::coil;
  std::size_t i = 0;
  while (i < in.size()) {
    const auto at = static_cast<std::uint16_t>(address + i);
    const MappedPoint* p = map_.at(table, at);
    // A write must start at a point and cover all its registers.
    if (p == nullptr || p->address != at) return Exception::illegal_data_address;
    const std::size_t count = bits ? 1 : p->spec.register_count();
    if (i + count > in.size()) return Exception::illegal_data_address;
    if (p->spec.access() != Access::read_write) return Exception::illegal_data_address;
    // backend.h: beyond the session's level is exception 01, and the only reason for it.
    if (required_level(*p) > session.access) return Exception::illegal_function;
    Value v;
    if (bits) {
      v = std::int64_t{in[i] != 0 ? 1 : 0};
    } else {
      std::array<std::uint16_t, 2> swapped{};
      auto words = in.subspan(i, count);
      if (session.word_order == modbus::WordOrder::little && has_word_order(p->spec)) {
        swapped = {words[1], words[0]};
        words = swapped;
      }
      auto decoded = decode_value(p->spec, words);
      if (!decoded) return Exception::illegal_data_value;
      v = std::move(*decoded);
      const double x = as_double(v);
      if ((p->spec.min != 0.0 || p->spec.max != 0.0) && (x < p->spec.min || x > p->spec.max)) {
        return Exception::illegal_data_value;
      }
    }
    parts.push_back({p, std::move(v)});
    i += count;
  }
  return Exception::none;
}

Exception Device::submit(const modbus::Session& session, Table table, std::uint16_t address,
                         std::span<const std::uint16_t> in, modbus::WriteDone done, TimePoint now,
                         Origin origin) {
  std::vector<Part> parts;
  if (const Exception e = validate(session, table, address, in, parts); e != Exception::none) {
    return e;
  }
  return enqueue(session, std::move(parts), std::move(done), now, origin);
}

Exception Device::write_points(const modbus::Session& session, std::span<const PointWrite> points,
                               modbus::WriteDone done, TimePoint now) {
  modbus::Session in_map_order = session;
  in_map_order.word_order = modbus::WordOrder::big;  // encode_value's order
  std::vector<Part> parts;
  for (const PointWrite& w : points) {
    const PointSpec& spec = w.point->spec;
    const bool bits = spec.table == Table::coil;
    std::array<std::uint16_t, 2> regs{};
    const std::size_t count = bits ? 1 : spec.register_count();
    if (count > regs.size()) return Exception::illegal_data_address;  // strings are not writable
    const auto words = std::span(regs).first(count);
    if (bits) {
      const double x = as_double(w.value);
      if (x != 0.0 && x != 1.0) return Exception::illegal_data_value;
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
                                   : 1e-6 * std::fabs(step);
      if (!held || std::fabs(as_double(*held) - asked) > tolerance) {
        return Exception::illegal_data_value;
      }
    }
    std::vector<Part> one;
    if (const Exception e = validate(in_map_order, spec.table, w.point->address, words, one);
        e != Exception::none) {
      return e;
    }
    parts.insert(parts.end(), one.begin(), one.end());
  }
  if (parts.empty()) return Exception::illegal_data_value;
  return enqueue(session, std::move(parts), std::move(done), now, Origin::plc);
}

Exception Device::enqueue(const modbus::Session& session, std::vector<Part> parts,
                          modbus::WriteDone done, TimePoint now, Origin origin) {
  const bool feeds = origin == Origin::plc && session.feeds_failsafe;
  const auto writes = [&](CommonWrite kind) {
    return std::any_of(parts.begin(), parts.end(),
                       [kind](const Part& p) { return write_kind(*p.point) == kind; });
  };
  // A valid write to command, setpoint or heartbeat proves the PLC is there, whatever the drive
  // then makes of it (even 0x0B while comm_lost).
  if (feeds && (writes(CommonWrite::command) || writes(CommonWrite::setpoint) ||
                writes(CommonWrite::heartbeat))) {
    failsafe_.fed(now);
  }
  // One request writing setpoint and command together means "run at this speed": the setpoint
  // applies first, whatever the address order.
  std::stable_partition(parts.begin(), parts.end(),
                        [](const Part& p) { return write_kind(*p.point) != CommonWrite::command; });
  // A drive that stopped answering cannot take anything: say so now rather than after a
  // timeout. The heartbeat alone is the gateway's and always succeeds.
  const bool heartbeat_only =
      parts.size() == 1 && write_kind(*parts[0].point) == CommonWrite::heartbeat;
  if (comm_lost() && !heartbeat_only) return Exception::gateway_target_failed;

  // The driver judges the whole request before any part of it is applied.
  std::vector<WriteOp> ops;
  for (const Part& p : parts) {
    if (auto op = op_of(*p.point, p.value)) ops.push_back(std::move(*op));
  }
  if (!ops.empty()) {
    if (const WriteCheck c = driver_->check(ops); c != WriteCheck::ok) return to_exception(c);
  }

  auto owned = std::make_unique<Request>();
  Request* r = owned.get();
  r->parts = std::move(parts);
  r->feeds_failsafe = feeds;
  r->done = std::move(done);
  requests_.push_back(std::move(owned));
  Exception failure = Exception::none;
  const Progress progress = advance(*r, now, failure);
  if (progress == Progress::failed) r->done = nullptr;  // answered by the return value instead
  if (progress != Progress::waiting) finish(r, failure);
  publish(now);
  if (progress == Progress::waiting && kick_) kick_();
  return failure;
}

// Applies parts from r.next on until one is pending or fails.
Device::Progress Device::advance(Request& r, TimePoint now, Exception& failure) {
  while (r.next < r.parts.size()) {
    const Part& part = r.parts[r.next++];
    const std::optional<WriteOp> maybe_op = op_of(*part.point, part.value);
    if (!maybe_op) {
      heartbeat_ = static_cast<std::uint16_t>(whole(part.value));
      image_stale_ = true;
      continue;
    }
    const WriteOp& op = *maybe_op;
    const Ticket t = next_ticket_++;
    const WriteStatus s = driver_->apply(op, t, now);
    image_stale_ = true;
    const bool taken = s == WriteStatus::done || s == WriteStatus::pending;
    if (taken && r.feeds_failsafe && op.target == WriteOp::Target::command && is_run(op.command) &&
        failsafe_.reset(now)) {
      log_->info("device {}: failsafe reset by {} from Modbus", config_.name,
                 to_string(op.command));
    }
    switch (s) {
      case WriteStatus::done:
        continue;
      case WriteStatus::pending:
        // Each part gets the driver's whole write_timeout from when it is applied: the driver's
        // own deadline (shorter) fails it first, so a part the PLC was told failed is never
        // still on its way to the drive.
        r.waiting = t;
        r.deadline = now + traits_.write_timeout;
        return Progress::waiting;
      case WriteStatus::invalid_value:
        failure = Exception::illegal_data_value;
        return Progress::failed;
      case WriteStatus::refused:
        failure = Exception::server_device_failure;
        return Progress::failed;
    }
  }
  return Progress::done;
}

void Device::settle(const Completion& c, TimePoint now) {
  const auto it = std::find_if(requests_.begin(), requests_.end(),
                               [&](const auto& r) { return r->waiting == c.ticket; });
  if (it == requests_.end()) return;  // its request timed out already
  Request* r = it->get();
  r->waiting.reset();
  if (c.result != WriteResult::ok) {
    finish(r, to_exception(c.result));  // the parts after it are never applied
    return;
  }
  Exception failure = Exception::none;
  const Progress progress = advance(*r, now, failure);
  if (progress != Progress::waiting) finish(r, failure);
  if (progress == Progress::waiting && kick_) kick_();
}

void Device::finish(const Request* r, Exception e) {
  const auto it = std::find_if(requests_.begin(), requests_.end(),
                               [r](const auto& owned) { return owned.get() == r; });
  if (it == requests_.end()) return;
  const std::unique_ptr<Request> owned = std::move(*it);
  requests_.erase(it);
  if (owned->done) owned->done(e);
}

void Device::expire_requests(TimePoint now) {
  std::vector<const Request*> late;
  for (const auto& r : requests_) {
    if (now >= r->deadline) late.push_back(r.get());
  }
  for (const Request* r : late) finish(r, Exception::gateway_target_failed);
}

void Device::fail_pending(Exception why) {
  auto failing = std::move(requests_);
  requests_.clear();
  for (auto& r : failing) {
    if (r->done) r->done(why);
  }
}

}  // namespace drivegate
