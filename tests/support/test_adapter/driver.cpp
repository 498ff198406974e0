// TestDriveDriver: the poll, the writes, and what the bus engine hands back.
#include "driver.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <variant>
#include <vector>

namespace drivegate::testdrive {
namespace {

constexpr Millis kReplyTimeout{100};
constexpr Millis kCommTimeout{3000};
constexpr Millis kInterFrameGap{2};
// Well inside kCommTimeout: a write to a drive that stopped answering fails before comm_lost.
constexpr Millis kWriteTimeout{2000};
// The driver fails a write it could not send by then, before the gateway's backstop.
constexpr Millis kSendBy = kWriteTimeout - kDeadlineMargin;
constexpr std::uint8_t kAttempts = 3;
// A write goes on the line (again) only when its turn of attempts ends by its send-by: none goes
// out after the gateway told the client it failed.
constexpr Millis kTurn = kAttempts * kReplyTimeout;

Fault unified(std::uint8_t native) {
  switch (static_cast<NativeFault>(native)) {
    case NativeFault::none:
      return Fault::none;
    case NativeFault::over_current:
      return Fault::over_current;
    case NativeFault::stall:
      return Fault::stall;
    case NativeFault::over_temperature:
      return Fault::drive_over_temperature;
  }
  return Fault::other;
}

// The time accel's arg says, in seconds (100 ms units, codec.h).
double seconds_of(std::uint16_t accel_100ms) {
  return accel_100ms / 10.0;
}

std::vector<PointSpec> make_points() {
  return {input_point("drive_state", PointType::u16, "",
                      "the drive's state byte: bit 0 running, bit 1 reverse"),
          holding_point("accel_time", PointType::u16, "s",
                        "the drive's time from 0 to 3000 rpm (and back); sent at once, in force "
                        "once the drive answered")
              .scaled(0.1)
              .limited(0.1, 6553.5)};
}

}  // namespace

Settings parse_settings(const Options& options) {
  Settings s;
  s.one_way = options.boolean("one_way");
  // 100 ms units, rounded to the nearest; the schema's range is what the frame carries.
  if (const std::int64_t ms = options.integer("accel_time_ms"); ms > 0) {
    s.accel_100ms =
        static_cast<std::uint16_t>(std::clamp<std::int64_t>((ms + 50) / 100, 1, 0xFFFF));
  }
  return s;
}

TestDriveDriver::TestDriveDriver(std::uint8_t address, Millis poll_interval, Settings settings)
    : DriverBase(make_points()),
      address_(address),
      poll_interval_(poll_interval),
      settings_(settings),
      setup_due_(settings.accel_100ms.has_value()) {
  // A drive starts with its factory accel time (codec.h) until one is written.
  values_[pt::accel_time] = seconds_of(kDefaultAccel100ms);
}

DriverTraits TestDriveDriver::traits() const {
  return {kCommTimeout, kWriteTimeout, kInterFrameGap};
}

Exchange TestDriveDriver::exchange(const Request& r) const {
  Exchange ex;
  ex.frame = encode(r);
  ex.timeout = kReplyTimeout;
  ex.attempts = kAttempts;
  return ex;
}

std::optional<Exchange> TestDriveDriver::next_exchange(TimePoint now) {
  writes_.expire_after(now);
  writes_.settle_if([now](const Writes::Entry& e) { return !e.sent && now + kTurn > e.deadline; },
                    WriteResult::no_response);
  if (setup_due_) {  // before anything else, each time the drive is reached
    in_flight_ = Op::accel;
    write_on_line_ = false;
    last_sent_ = now;
    return exchange({address_, Op::accel, *settings_.accel_100ms});
  }
  if (Writes::Entry* w = writes_.first_unsent(); w != nullptr && w == &writes_.front()) {
    w->sent = true;
    in_flight_ = w->job.request.op;
    write_on_line_ = true;
    last_sent_ = now;
    return exchange(w->job.request);
  }
  if (next_poll_ && now < *next_poll_) return std::nullopt;
  in_flight_ = Op::read;
  write_on_line_ = false;
  last_sent_ = now;
  return exchange({address_, Op::read, 0});
}

TimePoint TestDriveDriver::wake_at() const {
  if (setup_due_ || !writes_.empty()) return TimePoint::min();
  return next_poll_.value_or(TimePoint::min());
}

RxVerdict TestDriveDriver::on_receive(ByteView rx, TimePoint now) {
  (void)now;
  const Decoded<Reply> d = decode_reply(rx);
  if (d.status == DecodeStatus::incomplete) return {RxKind::incomplete, 0};
  if (d.status == DecodeStatus::bad) return damaged(d);
  // Only the answer to the request on the line is taken: another address's, or a late answer
  // to an earlier op, is foreign.
  if (!in_flight_ || d.frame.address != address_ || d.frame.op != *in_flight_) {
    return {RxKind::foreign, d.consumed};
  }
  // Refused: the request stays on the line, and the bus engine sends it again.
  if (d.frame.refused) return {RxKind::nack, d.consumed};
  if (write_on_line_) {
    settle_write(writes_.front().job.request);
  } else if (setup_due_ && *in_flight_ == Op::accel) {
    setup_due_ = false;
    values_[pt::accel_time] = seconds_of(*settings_.accel_100ms);
  }
  apply_reply(d.frame);
  in_flight_.reset();
  write_on_line_ = false;
  next_poll_ = last_sent_ + poll_interval_;
  return {RxKind::reply, d.consumed};
}

void TestDriveDriver::settle_write(const Request& sent) {
  if (sent.op == Op::accel) {
    values_[pt::accel_time] = seconds_of(sent.arg);
    if (settings_.accel_100ms) settings_.accel_100ms = sent.arg;  // what a returning drive gets
  } else {
    common_.command = writes_.front().job.command;
  }
  writes_.settle_front(WriteResult::ok);
}

void TestDriveDriver::apply_reply(const Reply& r) {
  common_.ready = true;
  common_.running = (r.state & kStateRunning) != 0;
  // A drive running on a run this driver did not send (found running: it was started before
  // this driver, by another one): the run it turns on is the command in force, at the speed it
  // turns (the protocol does not say what it was asked).
  if (common_.running && !is_run(common_.command)) {
    common_.command = (r.state & kStateReverse) != 0 ? Command::run_reverse : Command::run_forward;
    common_.setpoint_rpm = std::abs(r.speed_rpm);
  }
  common_.speed_rpm = r.speed_rpm;
  common_.native_fault = r.fault;
  common_.faults = {};
  if (const Fault f = unified(r.fault); f != Fault::none) common_.faults.set(f);
  values_[pt::drive_state] = std::int64_t{r.state};
}

void TestDriveDriver::on_no_reply(TimePoint now) {
  // Every attempt went unanswered: a write on the line goes again next turn, until it is
  // answered or its deadline passes (expire_after); the next poll goes at once.
  if (write_on_line_) writes_.front().sent = false;
  in_flight_.reset();
  write_on_line_ = false;
  next_poll_ = now;
}

void TestDriveDriver::on_comm_lost(TimePoint now) {
  (void)now;
  common_.ready = false;
  common_.speed_rpm = 0;
  common_.running = false;
  common_.command = Command::stop;
  in_flight_.reset();
  write_on_line_ = false;
  next_poll_.reset();
  writes_.settle_all(WriteResult::no_response);
  setup_due_ = settings_.accel_100ms.has_value();  // a drive back may have lost it
}

std::optional<Request> TestDriveDriver::run_request(Command c, std::int32_t rpm) const {
  const auto arg = static_cast<std::uint16_t>(std::abs(rpm));
  switch (c) {
    case Command::run_forward:
      return Request{address_, Op::run_forward, arg};
    case Command::run_reverse:
      return Request{address_, Op::run_reverse, arg};
    case Command::stop:
    case Command::quick_stop:
      return Request{address_, Op::stop, 0};
    case Command::reset_fault:
      return Request{address_, Op::reset, 0};
  }
  return std::nullopt;
}

std::optional<std::uint16_t> TestDriveDriver::accel_of(const Value& v) {
  if (!std::holds_alternative<std::int64_t>(v) && !std::holds_alternative<double>(v)) {
    return std::nullopt;
  }
  const std::int64_t n = std::llround(as_double(v) * 10.0);
  if (n < 1 || n > 0xFFFF) return std::nullopt;
  return static_cast<std::uint16_t>(n);
}

WriteCheck TestDriveDriver::judge(const WriteOp& op, bool& faulted) const {
  switch (op.target) {
    case WriteOp::Target::setpoint:
      return std::abs(op.rpm) <= kMaxRpm ? WriteCheck::ok : WriteCheck::invalid_value;
    case WriteOp::Target::command:
      if (op.command == Command::reset_fault) faulted = false;
      if (!is_run(op.command)) return WriteCheck::ok;
      if (op.command == Command::run_reverse && settings_.one_way) {
        return WriteCheck::invalid_value;  // it cannot turn that way
      }
      return faulted ? WriteCheck::refused : WriteCheck::ok;  // a tripped drive does not start
    case WriteOp::Target::point:
      if (op.point == pt::accel_time && accel_of(op.value)) return WriteCheck::ok;
      break;  // drive_state is read-only
    case WriteOp::Target::forward:
      break;
  }
  return WriteCheck::invalid_value;
}

WriteCheck TestDriveDriver::check(std::span<const WriteOp> request) const {
  bool faulted = common_.native_fault != 0;
  return check_in_order(request, {common_.command, common_.setpoint_rpm},
                        [&](const WriteOp& op, const Proposed&) { return judge(op, faulted); });
}

WriteStatus TestDriveDriver::apply(const WriteOp& op, Ticket t, TimePoint now) {
  if (const auto no = refusal(check({&op, 1}))) return *no;
  if (op.target == WriteOp::Target::point) {
    writes_.push({{address_, Op::accel, *accel_of(op.value)}, Command::stop}, t, now + kSendBy);
    return WriteStatus::pending;
  }
  if (op.target == WriteOp::Target::setpoint) {
    common_.setpoint_rpm = op.rpm;
    if (!is_run(common_.command)) return WriteStatus::done;  // carried by the next run
    const Command c = common_.command;
    writes_.push({*run_request(c, op.rpm), c}, t, now + kSendBy);
    return WriteStatus::pending;
  }
  // A quick stop stops: the command in force is then stop.
  const Command c = op.command == Command::quick_stop ? Command::stop : op.command;
  const Command in_force = c == Command::reset_fault ? common_.command : c;
  writes_.push({*run_request(c, common_.setpoint_rpm), in_force}, t, now + kSendBy);
  return WriteStatus::pending;
}

}  // namespace drivegate::testdrive
