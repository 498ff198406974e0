#include "driver.h"

#include <algorithm>
#include <utility>

#include "faults.h"
#include "op_state.h"
#include "points.h"

namespace drivegate::unicla {

EDriveDriver::EDriveDriver(std::uint8_t address, Millis poll_interval, const Settings& settings)
    : address_(address), poll_interval_(poll_interval), settings_(settings) {
  points_ = make_points();
  values_.resize(points_.size());
}

DriverTraits EDriveDriver::traits() const {
  DriverTraits t;
  const Millis one_read = settings_.attempts * unanswered_attempt(settings_.reply_timeout);
  t.comm_timeout = std::max(kMinCommTimeout, 4 * poll_interval_ + one_read);
  t.write_timeout = settings_.confirm_timeout + kWriteTimeoutSlack;
  t.inter_frame_gap = kInterFrameGap;
  return t;
}

Frame EDriveDriver::request(CommandByte cmd, MessageId id, Bytes payload) {
  Frame f;
  f.source = kMasterAddress;
  f.destination = address_;
  f.command = static_cast<std::uint8_t>(cmd);
  f.message_id = static_cast<std::uint8_t>(id);
  f.sequence = ++sequence_;  // "Inserted by master for its internal synchronisation purposes"
  f.payload = std::move(payload);
  return f;
}

// A write waiting for its confirmation has the status read again soon, not at the next poll.
TimePoint EDriveDriver::poll_due() const {
  if (awaiting_confirmation()) return std::min(next_poll_, last_read_ + kConfirmPoll);
  return next_poll_;
}

std::optional<Exchange> EDriveDriver::next_exchange(TimePoint now) {
  expire(now);
  if (auto write = next_write(now)) return write;
  if (now < poll_due()) return std::nullopt;
  return read(now);
}

// The read the poll plan is at: Build Information, then Running Limits, each repeated until
// answered, then Status.
Exchange EDriveDriver::read(TimePoint now) {
  MessageId id = MessageId::status;
  if (phase_ == Phase::build_information) id = MessageId::build_information;
  if (phase_ == Phase::running_limits) id = MessageId::running_limits;
  const Frame f = request(CommandByte::read, id);  // "Read: payload 0"
  awaiting_ = Awaiting{id, f.sequence};
  next_poll_ = now + poll_interval_;
  last_read_ = now;

  Exchange ex;
  ex.frame = encode(f);
  ex.reply = ReplyMode::expected;  // "Successful read commands always get a reply"
  ex.timeout = settings_.reply_timeout;
  ex.attempts = settings_.attempts;
  return ex;
}

TimePoint EDriveDriver::wake_at() const {
  if (has_unsent_write()) return TimePoint{};
  return std::min(poll_due(), earliest_deadline());
}

RxVerdict EDriveDriver::on_receive(ByteView rx, TimePoint now) {
  expire(now);
  const Decoded<Frame> d = decode(rx);
  if (const auto v = unless_frame(d)) return *v;
  const Frame& f = d.frame;
  // The reply is from the device to the master, a read, of the awaited message and sequence
  // ("Sequence Number": "The slave reply will contain this sequence number"). Any other good
  // frame is another drive's reply, a request on the line or a late reply.
  if (!awaiting_ || f.destination != kMasterAddress || f.source != address_ ||
      f.command != static_cast<std::uint8_t>(CommandByte::read) ||
      f.message_id != static_cast<std::uint8_t>(awaiting_->id) ||
      f.sequence != awaiting_->sequence) {
    return {RxKind::foreign, d.consumed};
  }
  const RxKind kind = on_reply(awaiting_->id, f, now);
  if (kind == RxKind::reply) awaiting_.reset();
  return {kind, d.consumed};
}

// The awaited reply, checked by the codec and matched by its header. A payload shorter than its
// message's ("Message IDs": 64 / 80 / 64 bytes) is not that reply: dropped as noise, so that the
// read times out and goes again; a longer one is read up to its size.
RxKind EDriveDriver::on_reply(MessageId id, const Frame& f, TimePoint now) {
  // A start-up read answered: the next phase's request goes out at once.
  const auto go_on = [&](Phase next) {
    phase_ = next;
    next_poll_ = now;
    return RxKind::reply;
  };
  switch (id) {
    case MessageId::build_information: {
      const auto b = parse_build_info(f.payload, settings_.byte_order);
      if (!b) return RxKind::noise;
      fill_build_info(values_, *b);
      build_speed_ = {b->min_speed, b->max_speed};
      return go_on(Phase::running_limits);
    }
    case MessageId::running_limits: {
      const auto l = parse_running_limits(f.payload, settings_.byte_order);
      if (!l) return RxKind::noise;
      fill_running_limits(values_, *l);
      // The configured limits bound Set Run State ("between the configured min and max reported
      // by eDrive"); a drive reporting none falls back to the compressor build's.
      limits_ = (l->min_speed == 0 && l->max_speed == 0) ? build_speed_
                                                         : SpeedLimits{l->min_speed, l->max_speed};
      control_enabled_ = l->control_enabled;
      return go_on(Phase::polling);
    }
    case MessageId::status: {
      const auto s = parse_status(f.payload, settings_.byte_order);
      if (!s) return RxKind::noise;
      on_status(*s, now);
      return RxKind::reply;
    }
    case MessageId::set_run_state:
    case MessageId::acknowledge_faults:
      break;  // never awaited: writes get no reply
  }
  return RxKind::noise;
}

void EDriveDriver::on_status(const Status& s, TimePoint now) {
  status_ = s;
  fill_status(values_, s);
  const FaultView fv = map_faults(s);
  common_.faults = fv.faults;
  common_.warning = fv.warning;
  common_.native_fault = fv.native;
  common_.speed_rpm = s.rpm;
  common_.running = is_running_state(s.op_state) || s.rpm > 0;
  // Online once the status, the data a PLC reads, is in too.
  common_.ready = phase_ == Phase::polling;
  confirm(s, now);
  // A compressor found running before anything was written to it (the gateway restarted, or
  // this device was changed by a reload) is shown as it runs: a run in force at its speed, so
  // that the registers never say stop over a turning compressor (README, "Choices").
  if (adopting_ && common_.ready) {
    adopting_ = false;
    if (is_running_state(s.op_state) && s.rpm > 0) {
      common_.command = Command::run_forward;
      common_.setpoint_rpm = s.rpm;
    }
  }
}

bool EDriveDriver::drive_runs() const {
  return status_ && is_running_state(status_->op_state);
}

void EDriveDriver::on_no_reply(TimePoint now) {
  awaiting_.reset();
  expire(now);  // a deadline that passed while the line was busy with this read
}

void EDriveDriver::on_comm_lost(TimePoint now) {
  // The drive may have been powered off or reconfigured: read its build and limits again, and
  // judge nothing by what it said before. What is in force stays: nothing undid it.
  awaiting_.reset();
  phase_ = Phase::build_information;
  common_.ready = false;
  limits_.reset();
  control_enabled_.reset();
  status_.reset();
  next_poll_ = std::min(next_poll_, now);
  fail_all();
}

}  // namespace drivegate::unicla
