// The stateful half of an adapter. A Driver never touches a file descriptor, a socket or a timer:
// the gateway's bus engine asks it what to send, hands it the bytes that came back and the time,
// and reads the state it publishes. This makes every driver testable with plain byte vectors.
//
// One bus engine serves every device on a serial line, one transaction at a time:
//   1. When the line is free it asks a device's driver for next_exchange(now): a device with a
//      Modbus write to send (the gateway hands a driver one part of a write at a time, on a write
//      turn), or one whose wake_at() has come, each round-robin, so a silent device costs the
//      others at most its own time budget (attempts x (timeout + guard)) per turn. Which of its
//      own frames goes first is the driver's choice; a part the gateway handed over goes first.
//   2. It waits traits().inter_frame_gap of line silence, writes Exchange::frame (discarding and
//      checking the echo on one-wire lines) and, if a reply is expected, collects bytes.
//   3. Every byte received, solicited or not, goes to on_receive() until the driver says a reply
//      is complete; bytes before that are kept, so a driver may return incomplete and see them
//      again with more appended. A driver takes a frame as the reply only when it matches the
//      request in flight (function, address or register echo, length, sequence): anything else
//      is foreign.
//   4. On timeout, a bad checksum or a NACK the engine resends the identical frame while attempts
//      remain, then calls on_no_reply(). After a timeout the line is kept quiet for a guard time
//      (the exchange's timeout) before anything is sent, and what arrives in it is dropped as late,
//      so a reply that comes after its timeout is never taken for the answer to a later request.
//      The engine owns retry counting, back-off of silent devices, comm_lost (no good frame for
//      traits().comm_timeout), data age (the last reply or frame carrying state, never an ack)
//      and all counters.
//   5. Writes and polls share the line fairly: when both wait, the engine alternates a write turn
//      and a poll turn, so no write load keeps any device on the line from being polled.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"
#include "drivegate/common.h"
#include "drivegate/line.h"
#include "drivegate/options.h"
#include "drivegate/point.h"

namespace drivegate {

using Clock = std::chrono::steady_clock;
using TimePoint = Clock::time_point;
using Millis = std::chrono::milliseconds;
// Line silences (the inter-frame gap) are kept to the microsecond: a few characters at 19200 baud
// are 2 ms, and whole milliseconds would add half of that again to every frame.
using Micros = std::chrono::microseconds;

enum class ReplyMode : std::uint8_t {
  expected,  // request / reply: wait for on_receive() to return RxKind::reply
  none,      // broadcast, or a write the device never acknowledges: done once written
};

// After an attempt that got no reply the engine keeps the line quiet for this guard time before
// it sends anything, and drops what arrives in it as a late reply (bus_engine.h).
constexpr Millis guard_time(Millis reply_timeout) {
  return reply_timeout;
}
// The most line time an unanswered attempt costs beyond its frame on the wire: for a driver's
// own deadlines that must hold a number of attempts.
constexpr Millis unanswered_attempt(Millis reply_timeout) {
  return reply_timeout + guard_time(reply_timeout);
}

// One transaction on the line.
struct Exchange {
  Bytes frame;
  ReplyMode reply = ReplyMode::expected;
  Millis timeout{100};        // per attempt: from the last byte written to a complete reply
  std::uint8_t attempts = 1;  // identical sends in this turn (1 = no retry)
};

enum class RxKind : std::uint8_t {
  incomplete,    // a frame may be under way: wait for more bytes (consumed is usually 0)
  reply,         // the awaited reply, carrying the drive's state, applied: the exchange is done
  ack,           // the awaited reply, carrying no state (a write's echo, a refused read): done,
                 // the drive answers, but data_age_ms does not restart (docs/safety.md)
  frame,         // a good frame that is not the awaited reply (a streamed status): applied
  nack,          // the device refused the frame at protocol level: resend
  bad_checksum,  // frame-shaped bytes whose checksum does not hold: dropped, resend
  foreign,       // a good frame for another address or sequence number: dropped, keep waiting
  noise,         // bytes that cannot start a frame: dropped, keep waiting
};

struct RxVerdict {
  RxKind kind = RxKind::incomplete;
  std::size_t consumed = 0;  // bytes of the input this verdict covers (dropped from the buffer)
};

// The verdict for bytes a codec rejected: a checksum failure costs the exchange an attempt,
// anything else is line noise to skip.
template <class Frame>
RxVerdict damaged(const Decoded<Frame>& d) {
  return {d.error == FrameError::bad_checksum ? RxKind::bad_checksum : RxKind::noise, d.consumed};
}

// The verdict for what a codec answered when it is not a frame: wait for more bytes when they are
// incomplete, damaged() when they are bad; nothing for a frame, which the driver reads itself.
//
//   const Decoded<Frame> d = decode(rx);
//   if (const auto v = unless_frame(d)) return *v;
template <class Frame>
std::optional<RxVerdict> unless_frame(const Decoded<Frame>& d) {
  switch (d.status) {
    case DecodeStatus::incomplete:
      return RxVerdict{RxKind::incomplete, 0};
    case DecodeStatus::bad:
      return damaged(d);
    case DecodeStatus::frame:
      break;
  }
  return std::nullopt;
}

// The largest speed the common block's speed_rpm (i16) carries either way; -32768 there means
// the speed is not known.
inline constexpr std::int32_t kMaxSpeedRpm = 32767;

// State every adapter publishes; the gateway turns it into the common register block.
struct CommonState {
  bool ready = false;    // the protocol's handshake is done (e.g. ping answered)
  bool running = false;  // the motor turns or is commanded to
  bool warning = false;
  FaultSet faults;                  // unified faults now active (comm_lost is added by the gateway)
  std::uint32_t native_fault = 0;   // the protocol's raw fault code or bitmask
  std::int32_t speed_rpm = 0;       // actual speed, negative in reverse where the drive says so
  std::int32_t setpoint_rpm = 0;    // the target the driver works towards
  Command command = Command::stop;  // the command in force
  // The drive's speed reading is not a number (NaN, infinite, beyond kMaxSpeedRpm): speed_rpm is
  // not to be shown, and the common block shows it unknown (README, "Register map").
  bool speed_unknown = false;
};

// Ticket of a write in flight; the driver reports its outcome through take_completions().
using Ticket = std::uint64_t;

// One part of a Modbus write request, as the gateway hands it to a driver. The gateway has checked
// table, access and the point's min / max already, and orders a request's setpoint before its
// command ("run at this speed").
struct WriteOp {
  // forward: a Modbus request PDU for a driver that forwards() (pass-through), sent as it is.
  enum class Target : std::uint8_t { command, setpoint, point, forward };
  Target target = Target::command;
  Command command = Command::stop;  // Target::command
  std::int32_t rpm = 0;             // Target::setpoint
  std::size_t point = 0;            // Target::point: index into points()
  Value value;                      // Target::point: the engineering value
  Bytes pdu;                        // Target::forward: function code and data, 1..253 bytes
  // When the client's last read of the drive's fault state before it asked showed a fault: the
  // trip it asked with in view (the gateway tracks each client's reads). A part applied later
  // (behind another, or after the request waited) carries the same. None: the client had read no
  // fault (or cannot tell: MQTT, the gateway's own writes), and a driver takes the request as
  // asked before anything it shows.
  std::optional<TimePoint> fault_seen;

  static WriteOp of_command(Command c) { return {Target::command, c, 0, 0, {}, {}, {}}; }
  static WriteOp of_setpoint(std::int32_t rpm) {
    return {Target::setpoint, Command::stop, rpm, 0, {}, {}, {}};
  }
  static WriteOp of_point(std::size_t index, Value v) {
    return {Target::point, Command::stop, 0, index, std::move(v), {}, {}};
  }
  static WriteOp of_forward(Bytes pdu) {
    return {Target::forward, Command::stop, 0, 0, {}, std::move(pdu), {}};
  }
};

// A driver's answer to a whole request before any part of it is applied.
enum class WriteCheck : std::uint8_t {
  ok,
  invalid_value,  // Modbus exception 0x03 (out of range, a command the drive cannot do)
  refused,        // Modbus exception 0x04 (the drive is in a state where it cannot)
};

// What apply() did with one part.
enum class WriteStatus : std::uint8_t {
  done,           // applied without bus traffic (e.g. a setpoint stored while stopped)
  pending,        // queued: a Completion with this ticket follows
  invalid_value,  // Modbus exception 0x03 (the state changed since check())
  refused,        // Modbus exception 0x04
};

enum class WriteResult : std::uint8_t {
  ok,
  refused,      // the device answered no (exception 0x04)
  no_response,  // the device did not answer or did not take it in time (exception 0x0B)
};

struct Completion {
  Ticket ticket;
  WriteResult result;
  // A forwarded request's answer (WriteOp::Target::forward, result ok): the device's reply PDU
  // exactly as it came, an exception reply included. Empty for every other write.
  Bytes reply = {};
};

// What a request would leave in force, part by part: a driver's check() judges each part against
// the state the parts before it would leave, not against the state now.
struct Proposed {
  Command command = Command::stop;
  std::int32_t setpoint_rpm = 0;
};

// The usual body of Driver::check(): `judge(op, proposed)` answers for one part; the setpoint and
// command of each accepted part are carried into the parts after it; the first answer that is not
// ok is the request's.
template <class Judge>
WriteCheck check_in_order(std::span<const WriteOp> request, Proposed proposed, Judge judge) {
  for (const WriteOp& op : request) {
    if (const WriteCheck c = judge(op, proposed); c != WriteCheck::ok) return c;
    if (op.target == WriteOp::Target::setpoint) proposed.setpoint_rpm = op.rpm;
    if (op.target == WriteOp::Target::command) proposed.command = op.command;
  }
  return WriteCheck::ok;
}

// For a driver's own write deadlines, which must end before the gateway's backstop
// (DriverTraits::write_timeout) so that nothing the PLC was told failed is still on its way.
// Another device's turn the line may be busy with before a write: its time budget, 1 s unless its
// configuration says otherwise (DeviceConfig::budget).
inline constexpr Millis kOtherTurnAllowance{1000};
// The default write_timeout below, kept as the floor of a driver's own.
inline constexpr Millis kWriteTimeoutFloor{3000};
// The gateway looks at its write deadlines every 100 ms (kTickPeriod): room so that a driver's
// own answer never races the gateway's.
inline constexpr Millis kDeadlineMargin{200};

struct DriverTraits {
  Millis comm_timeout{6000};  // no good frame for this long: comm_lost
  // The gateway fails a part of a write still pending this long after apply() took it (0x0B).
  // A backstop: the driver's own confirmation deadline should be shorter and fail it first, so
  // that nothing the PLC was told failed is still on its way to the drive.
  Millis write_timeout{3000};
  Micros inter_frame_gap{0};  // line silence the bus keeps before each frame
  // The drive's state (status, faults, speed) comes in several replies that each carry part of it
  // (a profile's blocks): the engine then dates it by Driver::state_read_at() rather than by the
  // last reply, and declares comm_lost once it is older than comm_timeout whatever else the
  // device answers.
  bool state_in_parts = false;
};

// What the gateway knows about the device when it creates the driver.
struct DeviceEnv {
  std::string name;
  std::uint32_t address = 0;  // native bus address; 0 where the protocol has none
  Millis poll_interval{500};
  Options options;           // validated against the adapter's schema, defaults filled in
  bool maintenance = false;  // created by `drivegate write`: maintenance-only writes allowed
  // One character on the line as the [[bus]] really runs it (its baud may not be the adapter's
  // native one): for a driver's own deadlines that must cover frames on the wire.
  std::chrono::nanoseconds char_time{0};
  // That [[bus]]'s settings, where there is a line (not when the register map is printed): for
  // an adapter whose devices each have their own line (a modbus profile's [line]) to refuse a bus
  // that does not run it.
  std::optional<LineDefaults> bus_line;
};

// What a driver owes its drive, and its clients, that a reload must not forget. A reload that
// changes a device makes a new driver for it, which starts from what it reads (Device::take_over
// hands this over): a stop owed after a trip (a drive its set value runs, which the fault clearing
// would restart) would otherwise be forgotten, and the turning drive adopted as running; and the
// setpoint such a drive's clients wrote while it stood still, held by the driver for its next run
// and never written to the drive (its set value reads 0), would be lost, refusing that run.
struct Owed {
  bool stop_after_trip = false;
  std::optional<std::int32_t> setpoint_held_rpm;
};

class Driver {
 public:
  virtual ~Driver() = default;

  [[nodiscard]] virtual DriverTraits traits() const = 0;
  // The adapter's own points, laid out after the common block. Fixed for the driver's lifetime.
  [[nodiscard]] virtual const std::vector<PointSpec>& points() const = 0;
  // Current values of points(), same order and size.
  [[nodiscard]] virtual const std::vector<Value>& values() const = 0;
  // A driver starts from what its drive reports, never from an assumed stop: once the drive
  // reports it runs (before any write), `command` and `setpoint_rpm` show that run, so a PLC
  // reads what the motor does and a write is judged against it (adapters/README.md, "Starting").
  [[nodiscard]] virtual const CommonState& common() const = 0;

  // The next transaction due at `now`, or nothing (then the engine asks again at wake_at()).
  virtual std::optional<Exchange> next_exchange(TimePoint now) = 0;
  // When the driver will next have something to send (keep-alive, poll, refresh).
  [[nodiscard]] virtual TimePoint wake_at() const = 0;
  virtual RxVerdict on_receive(ByteView rx, TimePoint now) = 0;
  // The exchange got no valid reply after all its attempts.
  virtual void on_no_reply(TimePoint now) = 0;
  // The engine declared comm_lost: forget the handshake, fail pending writes.
  virtual void on_comm_lost(TimePoint now) = 0;
  // A driver whose traits().state_in_parts: when the state common() publishes was read whole,
  // the time of the oldest reply it is made of; nothing while a part was not read since the
  // driver started or since comm_lost. Others leave it: the engine dates their state by each reply.
  [[nodiscard]] virtual std::optional<TimePoint> state_read_at() const { return std::nullopt; }

  // Writes. A Modbus request is all or nothing from the PLC's point of view: the gateway asks
  // check() about every part first (no side effects; nothing is applied unless it says ok), then
  // applies the parts one at a time in order, each only once the one before it settled (done,
  // or its Completion came back ok), so a later part finds the earlier ones in force. A part that
  // fails ends the request: the parts after it are never applied.
  [[nodiscard]] virtual WriteCheck check(std::span<const WriteOp> request) const = 0;
  virtual WriteStatus apply(const WriteOp& op, Ticket t, TimePoint now) = 0;
  // Outcomes of pending parts since the last call, appended to `out`.
  virtual void take_completions(std::vector<Completion>& out) = 0;
  // What the driver learned of its device that an operator must hear (a read plan it changed, a
  // point it can no longer read), one line each, since the last call, appended to `out`: the
  // gateway logs each as a warning, naming the device, after every driver call.
  virtual void take_notices(std::vector<std::string>& out) { (void)out; }

  // Pass-through (adapters whose devices speak Modbus themselves: adapters/modbus). True when
  // every Modbus request for this device's unit id is to be forwarded to it as it is, rather than
  // served from the register map: the gateway then hands the driver each request's PDU as a
  // WriteOp::Target::forward part (apply() -> pending; check() is not asked), on the device's
  // write turns like any write, and answers the client with the Completion's reply. The gateway
  // has judged the request already: one whole, well-formed request of a function whose length
  // it knows, holding no other frame, within the client's access (daemon/gateway/forward_access.h).
  [[nodiscard]] virtual bool forwards() const { return false; }

  // What the driver read beyond its options to make the device (a profile file), said so that
  // equal text means equal content: which file, and a fingerprint of what it held. Empty when it
  // read nothing. A reload compares it like a setting: a device whose file changed is a changed
  // device, started afresh with the new content.
  [[nodiscard]] virtual std::string files_read() const { return {}; }

  // What this driver owes its drive (Owed), and, on the driver a reload made in its place, taking
  // that over before its first exchange. Drivers that owe nothing leave both.
  [[nodiscard]] virtual Owed owed() const { return {}; }
  virtual void take_over(const Owed& owed) { (void)owed; }
};

}  // namespace drivegate
