#include "driver.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "line_timing.h"
#include "profile_options.h"
#include "rejected.h"
#include "values.h"

namespace drivegate::modbus_device {
namespace {

// Exception 02, illegal data address (Application Protocol 7): the slave lacks a register the
// block covers. Any other exception (04 failure, 05 acknowledge, 06 busy...) may pass.
constexpr std::uint8_t kIllegalAddress = 0x02;
// A block read before is searched only once the slave refused it with 02 this many times in a
// row: a drive may refuse a register while busy, and one glitch must not shrink the plan.
constexpr int kRefusalsBeforeSearch = 3;

// "holding 202" or "holding 202..203".
std::string span_text(Table t, std::uint32_t start, std::uint32_t count) {
  std::string s =
      std::string(kProfileTableNames.at(static_cast<std::size_t>(t))) + " " + std::to_string(start);
  if (count > 1) s += ".." + std::to_string(start + count - 1);
  return s;
}

// The register-map face of a profile point.
PointSpec spec_of(const ProfilePoint& p) {
  PointSpec s;
  s.name = p.name;
  s.table = p.table;
  s.type = served_type(p);
  // A float register holds the value, a string's hold text.
  const bool own_value =
      p.type == ValueType::f32 || p.type == ValueType::f64 || p.type == ValueType::string;
  s.scale = own_value ? 1.0 : p.scale;
  s.string_registers = p.type == ValueType::string ? p.registers : 0;
  s.labels = p.labels;
  s.bit_labels = p.bit_labels;
  s.unit = p.unit;
  s.description = p.description;
  s.trend = p.trend;
  switch (p.access) {
    case PointAccess::read:  // a holding register or coil the profile keeps read-only
      s.write_level = PointSpec::WriteLevel::none;
      break;
    case PointAccess::operate:
      s.write_level = PointSpec::WriteLevel::operate;
      break;
    case PointAccess::maintain:
      break;
  }
  if (p.writable() && (p.min || p.max)) {
    s.min = p.min.value_or(-1e12);
    s.max = p.max.value_or(1e12);
  }
  return s;
}

// A speed in rpm as the common block carries it: nothing for NaN, an infinity or a speed beyond
// kMaxSpeedRpm either way.
std::optional<std::int32_t> rpm_of(double speed) {
  const double rpm = std::round(speed);
  if (!std::isfinite(rpm) || std::fabs(rpm) > kMaxSpeedRpm) return std::nullopt;
  return static_cast<std::int32_t>(rpm);
}

// The unified fault a native code stands for: its entry in the map, or for a bit field the
// lowest set bit that is named (none when no bit is set); `other` otherwise.
Fault fault_of(const FaultBinding& b, std::uint32_t native) {
  if (b.bits.empty()) {
    const auto it = b.map.find(native);
    return it != b.map.end() ? it->second : b.other;
  }
  if (native == 0) return Fault::none;
  for (const auto& [bit, fault] : b.bits) {
    if (((native >> bit) & 1u) != 0) return fault;
  }
  return b.other;
}

}  // namespace

ModbusDriver::ModbusDriver(std::uint8_t address, Profile profile, Timing timing,
                           Millis poll_interval, std::string files_read)
    : profile_(std::move(profile)),
      layouts_(write_layouts(profile_)),
      speed_scale_(
          rpm_scale(profile_.common.speed_factor, profile_.common.speed_offset, profile_.options)),
      setpoint_scale_(rpm_scale(profile_.common.setpoint_factor, profile_.common.setpoint_offset,
                                profile_.options)),
      files_read_(std::move(files_read)),
      address_(address),
      timing_(timing),
      poll_interval_(poll_interval),
      exposed_index_(profile_.points.size()),
      raw_(profile_.points.size()),
      reading_(profile_.points.size()),
      refused_(profile_.points.size(), false) {
  // Every point not bound to the common block is one of the device's own.
  const std::vector<bool> bound = profile_.bound_to_common();
  const CommonBindings& c = profile_.common;
  std::vector<bool> state(profile_.points.size(), false);
  if (c.speed_rpm) state[*c.speed_rpm] = true;
  for (const auto& b : {c.running, c.fault}) {
    if (b) state[b->point] = true;
  }
  if (c.fault_code) state[c.fault_code->point] = true;
  for (std::size_t i = 0; i < state.size(); ++i) {
    if (state[i]) state_points_.push_back(i);
  }
  for (std::size_t i = 0; i < profile_.points.size(); ++i) {
    if (bound[i]) continue;
    exposed_index_[i] = points_.size();
    exposed_.push_back(i);
    points_.push_back(spec_of(profile_.points[i]));
  }
  values_.resize(points_.size());
  // One group per poll interval; the device's own for points that name none.
  std::map<Millis, std::vector<std::size_t>> by_interval;
  for (std::size_t i = 0; i < profile_.points.size(); ++i) {
    const auto own = profile_.points[i].poll_ms;
    by_interval[own != 0 ? Millis(own) : poll_interval_].push_back(i);
  }
  for (auto& [interval, points] : by_interval) {
    Group g;
    g.interval = interval;
    g.points = std::move(points);
    plan(g);
    groups_.push_back(std::move(g));
  }
}

// The group's blocks: its points the slave serves, joined by the planner around the registers
// it refuses.
void ModbusDriver::plan(Group& g) const {
  std::vector<std::size_t> served;
  for (const std::size_t p : g.points) {
    if (!refused_[p]) served.push_back(p);
  }
  g.blocks = plan_reads(profile_, served, skipped_);
}

Micros ModbusDriver::inter_frame_gap() const {
  return modbus_device::inter_frame_gap(profile_.line.framing, timing_.char_time);
}

// The longest one exchange of this device takes.
Millis ModbusDriver::turn() const {
  return exchange_time(profile_.line.framing, timing_.char_time, Millis(profile_.modbus.timeout_ms),
                       timing_.attempts, longest_frame(profile_.line.framing));
}

Millis ModbusDriver::send_limit() const {
  return turn() + kOtherTurnAllowance;
}

DriverTraits ModbusDriver::traits() const {
  DriverTraits t;
  t.comm_timeout = timing_.comm_timeout;
  t.inter_frame_gap = inter_frame_gap();
  // A write settles within send_limit() and one turn of its own; a request holds at most a
  // setpoint and a command, and a command is as many writes as its longest sequence.
  std::size_t longest = 1;
  const CommonBindings& c = profile_.common;
  for (const auto& v : {c.stop, c.run_forward, c.run_reverse, c.reset_fault}) {
    if (v) longest = std::max(longest, v->sequence.size());
  }
  t.write_timeout = write_backstop(turn(), 1 + static_cast<int>(longest));
  t.state_in_parts = !state_points_.empty();
  return t;
}

// A drive that takes a user-defined write code may answer under it or under the code whose layout
// it has: the V&T and Honwin manuals describe 0x41 with 0x06's frame ("0x06 (0x41)") and print no
// reply of it. Either is the echo, which confirm() then checks.
bool ModbusDriver::Job::answered_by(std::uint8_t reply_function) const {
  return reply_function == function || (layout.code != 0 && reply_function == layout.like);
}

bool ModbusDriver::Job::refused_by(std::uint8_t reply_function) const {
  return (reply_function & kExceptionBit) != 0 &&
         answered_by(static_cast<std::uint8_t>(reply_function & ~kExceptionBit));
}

ModbusDriver::Job ModbusDriver::read_job(const Block& b) const {
  Job j;
  j.read = b;
  j.function = read_function(b.table);
  j.pdu = {j.function};
  put_be16(j.pdu, b.start);
  put_be16(j.pdu, b.count);
  return j;
}

Exchange ModbusDriver::exchange(const Job& j) const {
  Exchange ex;
  ex.frame = encode(profile_.line.framing, address_, j.pdu);
  ex.reply = ReplyMode::expected;
  // The profile's timeout, and the time the longest reply to this request takes on the wire.
  std::size_t reply_bytes = 8;
  if (j.read) reply_bytes = 5 + data_bytes(*j.read);
  if (profile_.line.framing == Framing::ascii) reply_bytes = 2 * reply_bytes + 3;
  ex.timeout = reply_timeout(Millis(profile_.modbus.timeout_ms), timing_.char_time, reply_bytes);
  ex.attempts = timing_.attempts;
  return ex;
}

std::optional<Exchange> ModbusDriver::next_exchange(TimePoint now) {
  last_now_ = now;
  writes_.expire_after(now);
  // The engine asks only once the exchange before ended; one it abandoned without a word still
  // owes its write an answer.
  fail_inflight();
  // A cycle whose last read was abandoned is over too.
  if (!unpublished_.empty()) end_of_read();
  while (!writes_.empty()) {
    Writes::Entry e = writes_.take_front();
    if (!ready_to_send(e)) continue;
    inflight_ = write_job(e);
    return exchange(*inflight_);
  }
  if (reads_.empty()) {
    for (Group& g : groups_) {
      if (now < g.due) continue;
      for (const Block& b : g.blocks) {
        // A block whose last read failed sits out cycles of its back-off (on_read_failed).
        if (reading_[b.points.front()].skip == 0) {
          reads_.push_back(b);
          continue;
        }
        for (const std::size_t p : b.points) {
          if (reading_[p].skip > 0) --reading_[p].skip;
        }
      }
      g.due = now + g.interval;
    }
  }
  // A search goes first: its block's points are unknown until it is read.
  if (!searches_.empty()) {
    inflight_ = read_job(*searches_.front().next());
    inflight_->probe = true;
    return exchange(*inflight_);
  }
  if (reads_.empty()) return std::nullopt;
  inflight_ = read_job(reads_.front());
  reads_.pop_front();
  return exchange(*inflight_);
}

TimePoint ModbusDriver::wake_at() const {
  if (!writes_.empty() || !reads_.empty() || !searches_.empty()) return last_now_;
  TimePoint next = TimePoint::max();
  for (const Group& g : groups_) {
    if (!g.blocks.empty()) next = std::min(next, g.due);
  }
  return next;
}

RxVerdict ModbusDriver::on_receive(ByteView rx, TimePoint now) {
  last_now_ = now;
  if (rx.empty()) return {};
  if (!inflight_) return {RxKind::noise, rx.size()};
  const Decoded<Adu> d = decode_reply(profile_.line.framing, rx, layouts_);
  switch (d.status) {
    case DecodeStatus::incomplete:
      return {};
    case DecodeStatus::bad:
      return rejected(profile_.line.framing, d, rx, address_);
    case DecodeStatus::frame:
      break;
  }
  const Adu& a = d.frame;
  const bool exception = inflight_->refused_by(a.pdu[0]) && a.pdu.size() == 2;
  if (a.address != address_ || (!inflight_->answered_by(a.pdu[0]) && !exception)) {
    return {RxKind::foreign, d.consumed};
  }
  if (inflight_->read && !exception) {
    // A read reply carries exactly the bytes asked for (Application Protocol 6.1 - 6.4).
    const Block& b = *inflight_->read;
    const std::size_t data = data_bytes(b);
    if (a.pdu.size() != 2 + data || a.pdu[1] != data) return {RxKind::foreign, d.consumed};
  }
  const Job job = std::move(*inflight_);
  inflight_.reset();
  if (job.write) {
    if (exception) {
      writes_.settle(*job.write, WriteResult::refused);
    } else {
      confirm(job, a.pdu);
    }
    return {RxKind::ack, d.consumed};  // an echo says nothing of the drive's state
  }
  if (exception) {
    if (job.probe && a.pdu[1] == kIllegalAddress) {
      on_probe(true);
    } else {
      // Any other refusal ends the search: the block is read again as planned, and searched
      // again once it is refused with 02 again.
      if (job.probe && !searches_.empty()) searches_.pop_front();
      on_read_failed(*job.read, a.pdu[1]);
    }
    end_of_read();
    return {RxKind::ack, d.consumed};
  }
  on_read(*job.read, a.pdu, now);
  if (job.probe && !searches_.empty()) on_probe(false);
  end_of_read();
  return {RxKind::reply, d.consumed};
}

void ModbusDriver::on_read(const Block& b, ByteView pdu, TimePoint now) {
  const ByteView data = pdu.subspan(2);
  for (const std::size_t i : b.points) {
    const ProfilePoint& p = profile_.points[i];
    std::vector<std::uint16_t> words;
    const std::size_t offset = p.address - b.start;
    if (is_bit_table(b.table)) {
      words.push_back(static_cast<std::uint16_t>((data[offset / 8] >> (offset % 8)) & 1u));
    } else {
      for (std::size_t w = 0; w < p.width(); ++w) {
        words.push_back(be16(data[2 * (offset + w)], data[2 * (offset + w) + 1]));
      }
    }
    raw_[i] = std::move(words);
    unpublished_.emplace_back(i, now);
  }
  served_ = true;
  refusing_ = false;
  ++blocks_read_;
}

// The cycle is over once no read of it is left, nor a search it began.
void ModbusDriver::end_of_read() {
  if (reads_.empty() && searches_.empty()) publish();
}

// The values, the read times and the common block of the cycle's reads, at once.
void ModbusDriver::publish() {
  for (const auto& [i, at] : unpublished_) {
    if (const auto e = exposed_index_[i]) {
      values_[*e] = raw_[i] ? value_of(profile_.points[i], *raw_[i]) : Value{};
    }
    reading_[i] = Reading{at, 0, 0, 0};
  }
  unpublished_.clear();
  update_common();
  check_tripped_at_start();
  adopt();
}

// A fault shown, but for a speed the drive cannot read (sensor_fault): that is no trip, the
// motor may turn.
bool ModbusDriver::tripped() const {
  FaultSet faults = common_.faults;
  faults.clear(Fault::sensor_fault);
  return !faults.empty();
}

// A drive its set value runs: the stop it is owed after a trip, and the setpoint held for its next
// run while no run is in force (with one, its set value holds it, read back at adoption).
Owed ModbusDriver::owed() const {
  Owed o{.stop_after_trip = stop_owed_, .setpoint_held_rpm = std::nullopt};
  if (profile_.common.setpoint_runs && !is_run(common_.command) && common_.setpoint_rpm != 0) {
    o.setpoint_held_rpm = common_.setpoint_rpm;
  }
  return o;
}

// A reload made this driver in place of one that owed its drive a stop after a trip: owed here
// too, so that the drive found turning (the fault cleared meanwhile) is stopped, not adopted. The
// setpoint the old one held is held here, so that the clients' next run runs at it.
void ModbusDriver::take_over(const Owed& owed) {
  if (!profile_.common.setpoint_runs) return;
  if (owed.stop_after_trip) stop_owed_ = true;
  // One this profile cannot write (its range or options changed) is not held: the PLC reads 0 and
  // its bare run is refused with nothing to run at, as it would be at any start.
  if (owed.setpoint_held_rpm && run_words(*owed.setpoint_held_rpm)) {
    setpoint_taken_over_ = owed.setpoint_held_rpm;
    common_.setpoint_rpm = *owed.setpoint_held_rpm;
  }
}

// A drive its set value runs, found tripped with that value not 0 at the first whole cycle, would
// restart when the fault clears: a stop is owed, as after a trip seen while it ran
// (update_common), whatever a client wrote meanwhile. A speed it cannot read (sensor_fault) is no
// trip.
void ModbusDriver::check_tripped_at_start() {
  const CommonBindings& c = profile_.common;
  if (start_checked_ || !common_.ready) return;
  start_checked_ = true;
  if (!c.setpoint_runs || !tripped() || engineering(c.setpoint_rpm).value_or(0) == 0) return;
  stop_owed_ = true;
  stop_after_trip();
}

// A slave that refuses a block with exception 02 (illegal data address) may lack a register in
// it: the block is searched (to_search, GapSearch) from the next exchange on, so one missing
// register never costs the device its other points. Any other refusal, a block refused with 02
// that is not searched, and a block left unanswered are a read that failed: its points are
// asked again at their next cycle, then after 1, 3, 7... cycles sat out (twice the wait each
// time, at most the comm timeout apart, or every cycle where one is longer), and the device's
// own points among them are unknown meanwhile. A part of the drive's state that is not read ages
// the state (state_read_at), which the data age and comm_lost then tell.
void ModbusDriver::on_read_failed(const Block& b, std::optional<std::uint8_t> code) {
  const bool illegal = code == kIllegalAddress;
  for (const std::size_t p : b.points) {
    if (illegal) ++reading_[p].illegal;
  }
  if (illegal && to_search(b)) {
    for (const std::size_t p : b.points) {
      if (const auto e = exposed_index_[p]) values_[*e] = Value{};
    }
    searches_.emplace_back(profile_, b);
    return;
  }
  back_off(b);
}

void ModbusDriver::back_off(const Block& b) {
  for (const std::size_t p : b.points) {
    Reading& r = reading_[p];
    const auto most = std::max<std::int64_t>(timing_.comm_timeout / interval_of(p) - 1, 0);
    const int shift = std::min(r.failures, 20);
    ++r.failures;
    r.skip = static_cast<int>(std::min<std::int64_t>((std::int64_t{1} << shift) - 1, most));
    if (const auto e = exposed_index_[p]) values_[*e] = Value{};
  }
}

// Searched: a block of a slave not known to refuse everything, not being searched already, that was
// never read whole (one of its points never read) or was refused with 02 kRefusalsBeforeSearch
// times in a row.
bool ModbusDriver::to_search(const Block& b) const {
  if (refusing_) return false;
  for (const GapSearch& s : searches_) {
    if (s.block() == b) return false;
  }
  const bool unread =
      std::any_of(b.points.begin(), b.points.end(), [&](std::size_t p) { return !reading_[p].at; });
  const bool refused = std::all_of(b.points.begin(), b.points.end(), [&](std::size_t p) {
    return reading_[p].illegal >= kRefusalsBeforeSearch;
  });
  return unread || refused;
}

void ModbusDriver::on_probe(bool refused) {
  GapSearch& s = searches_.front();
  const bool found = !s.refused().empty();
  s.answered(refused);
  // Nothing read yet, and a refusal after a part found refused (or a search that found one
  // and ends): the slave refuses everything. Nothing is skipped.
  if (!served_ && !s.refused().empty() && ((refused && found) || s.done())) {
    refusing_ = true;
    const Block b = s.block();
    searches_.pop_front();
    notices_.push_back("the slave refuses every read it was asked (exception 02): " +
                       span_text(b.table, b.start, b.count) + " is not searched further");
    back_off(b);
    return;
  }
  if (!s.done()) return;
  const GapSearch done = std::move(s);
  searches_.pop_front();
  learn(done);
}

void ModbusDriver::learn(const GapSearch& s) {
  const Table t = s.block().table;
  for (const GapSearch::Part& part : s.refused()) {
    for (std::uint32_t a = part.start; a < std::uint32_t{part.start} + part.count; ++a) {
      skipped_.insert({t, static_cast<std::uint16_t>(a)});
    }
    if (!part.point) continue;
    refused_[*part.point] = true;
    raw_[*part.point].reset();
    if (const auto e = exposed_index_[*part.point]) values_[*e] = Value{};
    notices_.push_back("point " + profile_.points[*part.point].name + " (" +
                       span_text(t, part.start, part.count) +
                       ") is refused by the slave (exception 02): unknown from now on");
  }
  if (!s.refused().empty()) {
    plan_changed_ = true;
    // The cycle under way was of the old plan: every group is read anew by the new one.
    reads_.clear();
    for (Group& g : groups_) {
      plan(g);
      g.due = last_now_;
    }
  }
  // Once no search is left: the plan as it is now, in one line.
  if (plan_changed_ && searches_.empty()) {
    plan_changed_ = false;
    notices_.push_back(plan_text());
  }
}

// "read plan: holding 0..1, input 200; skips holding 202..203 (refused by the slave)".
std::string ModbusDriver::plan_text() const {
  std::string s = "read plan:";
  const char* sep = " ";
  for (const Group& g : groups_) {
    for (const Block& b : g.blocks) {
      s += sep + span_text(b.table, b.start, b.count);
      sep = ", ";
    }
  }
  if (sep[0] == ' ') s += " nothing";
  s += "; skips";
  // Runs of skipped registers, each as one span.
  sep = " ";
  for (auto it = skipped_.begin(); it != skipped_.end();) {
    auto end = std::next(it);
    std::uint32_t count = 1;
    while (end != skipped_.end() && end->first == it->first && end->second == it->second + count) {
      ++end;
      ++count;
    }
    s += sep + span_text(it->first, it->second, count);
    sep = ", ";
    it = end;
  }
  return s + " (refused by the slave, until drivegated restarts or a reload changes the device)";
}

Millis ModbusDriver::interval_of(std::size_t point) const {
  const auto own = profile_.points[point].poll_ms;
  return own != 0 ? Millis(own) : poll_interval_;
}

void ModbusDriver::on_no_reply(TimePoint now) {
  last_now_ = now;
  // A search whose read goes unanswered ends: begun again once the block is refused again.
  if (inflight_ && inflight_->probe && !searches_.empty()) searches_.pop_front();
  const bool read = inflight_ && inflight_->read;
  if (read) on_read_failed(*inflight_->read, std::nullopt);
  fail_inflight();
  if (read) end_of_read();
}

void ModbusDriver::on_comm_lost(TimePoint now) {
  last_now_ = now;
  fail_inflight();
  // Nothing waiting is sent once the slave answers again: the PLC was told these failed.
  writes_.settle_all(WriteResult::no_response);
  reads_.clear();
  unpublished_.clear();
  blocks_read_ = 0;
  common_.ready = false;
  // Its state is whole again only once every part of it was read anew. What it refused stays
  // skipped (a slave that lacked a register still lacks it; one that refused everything was
  // never searched): a device whose state it refuses goes comm_lost once, not in a loop.
  std::fill(reading_.begin(), reading_.end(), Reading{});
  // And nothing read before the loss stands beside what is read after it: a fault bit read anew
  // beside a code not yet read again is a fault of kind other, never the kind read before.
  std::fill(raw_.begin(), raw_.end(), std::nullopt);
  bit_set_at_.reset();
  faults_read_ = false;
  // A trip shown before the loss is not the one read after it (the fault may have cleared and
  // another come, unseen): a run asked with the first shown is no run asked with the second.
  trip_shown_at_.reset();
  run_in_trip_ = false;
  searches_.clear();
  served_ = false;
  for (Group& g : groups_) g.due = now;
}

std::optional<TimePoint> ModbusDriver::state_read_at() const {
  std::optional<TimePoint> oldest;
  for (const std::size_t p : state_points_) {
    const auto at = reading_[p].at;
    if (!at) return std::nullopt;
    if (!oldest || *at < *oldest) oldest = at;
  }
  return oldest;
}

std::optional<double> ModbusDriver::engineering(std::optional<std::size_t> point) const {
  if (!point || !raw_[*point]) return std::nullopt;
  const ProfilePoint& p = profile_.points[*point];
  return raw_of(p, *raw_[*point]) * p.scale;
}

std::optional<bool> ModbusDriver::bit_of(const std::optional<BitBinding>& b) const {
  if (!b || !raw_[b->point]) return std::nullopt;
  // Any of the binding's bits of the point's value (a bit point's value is its bit 0), or the
  // value one of its codes.
  const std::uint16_t value = masked(profile_.points[b->point], (*raw_[b->point])[0]);
  if (!b->values.empty())
    return std::find(b->values.begin(), b->values.end(), value) != b->values.end();
  return (value & b->mask()) != 0;
}

void ModbusDriver::update_common() {
  const CommonBindings& c = profile_.common;
  if (auto speed = engineering(c.speed_rpm)) {
    *speed = speed_scale_.rpm(*speed);
    // A speed is a number the common block carries, by the point's own type and signedness; NaN,
    // an infinity or a speed beyond it (2^32 from a float, 4294967295 from a u32) is none.
    const auto rpm = rpm_of(*speed);
    common_.speed_unknown = !rpm;
    common_.speed_rpm = rpm.value_or(0);
  }
  if (const auto running = bit_of(c.running)) {
    common_.running = *running;
  } else if (!c.running && c.speed_rpm && raw_[*c.speed_rpm]) {
    // No run bit: a turning motor runs, and one whose speed is not known may be turning.
    common_.running = common_.speed_unknown || common_.speed_rpm != 0;
  }
  // The fault bit, where there is one, says whether a fault is active; the fault code which.
  FaultSet faults;
  std::optional<Fault> coded;
  if (c.fault_code && raw_[c.fault_code->point]) {
    const ProfilePoint& p = profile_.points[c.fault_code->point];
    const double raw = raw_of(p, *raw_[c.fault_code->point]);
    if (std::isfinite(raw) && raw == std::trunc(raw) && std::fabs(raw) <= 4294967295.0) {
      const auto native = static_cast<std::uint32_t>(static_cast<std::int64_t>(raw));
      common_.native_fault = native;
      coded = fault_of(*c.fault_code, native);
    } else {
      // A code that is not a whole number (a float point reading NaN): no code, but something
      // is wrong, whatever the profile names the codes it does not map.
      common_.native_fault = 0xFFFFFFFF;
      coded = Fault::other;
    }
  }
  const auto fault_bit = bit_of(c.fault);
  bool active = fault_bit ? *fault_bit : (coded && *coded != Fault::none);
  // The fault bit and its code in two reads of a cycle: a trip or a reset can land between them.
  // Only the first read of the bit set beside a code that says none can be such a race: a code read
  // before that bit, with no fault shown yet, missed the trip (shown whole at the next cycle); a
  // code read after it, beside a fault shown, saw the reset first (the kinds shown stand for this
  // cycle). Any other fault bit beside a code saying none is a fault of kind `other`.
  FaultSet before = faults_read_ ? common_.faults : FaultSet{};
  before.clear(Fault::sensor_fault);
  const bool bare = active && fault_bit && coded && *coded == Fault::none;
  if (!bare) bit_set_at_.reset();
  if (bare) {
    const auto bit_at = reading_[c.fault->point].at;
    const auto code_at = reading_[c.fault_code->point].at;
    if (!bit_set_at_) bit_set_at_ = bit_at;
    const bool first = bit_at && bit_at == bit_set_at_ && code_at;
    if (first && *code_at < *bit_at && before.empty()) {
      active = false;
    } else if (first && *code_at > *bit_at && !before.empty()) {
      faults = before;
    } else {
      faults.set(Fault::other);
    }
  } else if (active) {
    faults.set(coded && *coded != Fault::none ? *coded : Fault::other);
  }
  // A speed reading that is not a number is a measurement the drive cannot give: a fault of its
  // own, so that the PLC sees it (status bit fault) beside speed_rpm's unknown mark.
  if (common_.speed_unknown) faults.set(Fault::sensor_fault);
  common_.faults = faults;
  // A trip stops the output: the run in force is over.
  // A drive its set value runs shows no run bit: a fault ends its run whatever its speed (it may
  // be coasting), and the driver stops it, so that the fault clearing (by itself, or a reset from
  // its keypad) does not restart the motor while the command reads stop.
  // A run a client asked for while this trip was shown is not ended by it: the PLC asked with the
  // fault in view (a PLC that re-sends run each cycle would otherwise see the fan's set value
  // written and stopped in turn); the fan runs once the fault clears, as its command reads.
  if (!active) {
    run_in_trip_ = false;
    trip_shown_at_.reset();
  } else if (!trip_shown_at_) {
    trip_shown_at_ = last_now_;
  }
  const bool ends_run = c.setpoint_runs ? !run_in_trip_ : !common_.running;
  if (active && is_run(common_.command) && ends_run) {
    common_.command = Command::stop;
    if (c.setpoint_runs) stop_owed_ = true;
  }
  // Owed until the drive confirms a stop (or a client's run): written again while none is on its
  // way, after a refusal, no answer or a comm loss, backed off (stop_after_trip). A run waiting
  // while the fault is shown was asked before it was: over.
  if (stop_owed_) {
    if (active) settle_waiting_runs();
    stop_after_trip();
  }
  faults_read_ = true;
  const std::size_t blocks =
      std::accumulate(groups_.begin(), groups_.end(), std::size_t{0},
                      [](std::size_t n, const Group& g) { return n + g.blocks.size(); });
  // Ready once every block was read and the drive's state is whole.
  common_.ready = blocks_read_ >= blocks && (state_points_.empty() || state_read_at());
}

// A drive found running, before anything was written to it, runs on as it is: its run is the
// command in force (reverse where its speed is negative), its reference the setpoint, so that the
// registers never say stop over a turning motor. Adoption ends once every block was read once,
// or at the first write.
void ModbusDriver::adopt() {
  if (!adopting_ || !common_.ready) return;
  adopting_ = false;
  // A set value reading 0 beside a setpoint taken over from a reload: the drive stands still, and
  // the setpoint held for its next run is the one its clients wrote.
  if (const auto reference = engineering(profile_.common.setpoint_rpm)) {
    const auto rpm = rpm_of(setpoint_scale_.rpm(*reference));
    if (rpm && !(*reference == 0 && setpoint_taken_over_)) common_.setpoint_rpm = *rpm;
  }
  // A drive its set value runs is commanded to run by that value not 0, untripped (a speed it
  // cannot read, sensor_fault, is no trip: it may turn); with 0 it is not (one still turning is
  // coasting down from a stop). A tripped one was handled by check_tripped_at_start().
  // One a stop is owed to (its trip carried over a reload, Owed) is not adopted: the stop goes.
  const CommonBindings& c = profile_.common;
  if (c.setpoint_runs) {
    if (!stop_owed_ && !tripped() && !bit_set_at_ && engineering(c.setpoint_rpm).value_or(0) != 0)
      common_.command = Command::run_forward;
    return;
  }
  // A trip not shown yet (update_common) is no run to adopt either.
  if (!common_.running || !common_.faults.empty() || bit_set_at_) return;
  common_.command = common_.speed_rpm < 0 ? Command::run_reverse : Command::run_forward;
}

}  // namespace drivegate::modbus_device
