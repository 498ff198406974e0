// The driver alone, where the contract of include/drivegate/driver.h is about one call: the
// verdicts of on_receive(), check() judging a request with no side effects and exactly as apply()
// then takes its parts, and when the driver wants to be woken.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "codec.h"
#include "driver.h"
#include "points.h"

namespace drivegate::fdc1 {
namespace {

using namespace std::chrono_literals;

const test::OptionText kSlave = {{"slave_mode", "true"}};

// A driver from the adapter's own factory, and the controller played by hand: it streams
// `status` every 0.5 s, follows every speed frame (unless in alarm), and echoes programming frames.
struct Hand {
  explicit Hand(const test::OptionText& options = kSlave, bool maintenance = false) {
    DeviceEnv env;
    env.name = "fridge";
    env.options = test::options_of(drivegate_adapter, options);
    env.maintenance = maintenance;
    std::string error;
    d = drivegate_adapter.create_driver(env, error);
    EXPECT_NE(d, nullptr) << error;
  }

  // Everything the driver wants to send now, answered as the controller would.
  void exchanges() {
    while (auto ex = d->next_exchange(now)) {
      sent.push_back(ex->frame);
      const auto m = decode_master(ex->frame);
      ASSERT_EQ(m.status, DecodeStatus::frame);
      if (const auto* s = std::get_if<Speed>(&m.frame)) {
        speed = s->min_rpm;
      } else {
        const Bytes echo = encode_echo(std::get<Program>(m.frame));
        EXPECT_EQ(d->on_receive(echo, now).kind, RxKind::reply);
      }
    }
  }
  // Half a second: what is due goes out, then one status.
  void step() {
    exchanges();
    now += kStreamPeriod;
    (void)d->next_exchange(now);  // deadlines (the engine asks at wake_at())
    if (alarm == 0 && speed != 0) {
      status = Status{true, speed, 0, 1000};
    } else {
      status = Status{false, 0, alarm, 0};
    }
    const Bytes frame = encode_status(status);
    EXPECT_EQ(d->on_receive(frame, now).kind, RxKind::frame);
    exchanges();
  }
  WriteStatus apply(const WriteOp& op) { return d->apply(op, ++ticket, now); }
  // Steps until ticket `t` completes; its result.
  std::optional<WriteResult> settle(Ticket t) {
    for (int i = 0; i < 30; ++i) {
      std::vector<Completion> out;
      d->take_completions(out);
      for (const auto& c : out) {
        if (c.ticket == t) return c.result;
      }
      step();
    }
    return std::nullopt;
  }

  std::unique_ptr<Driver> d;
  TimePoint now = TimePoint{} + 1h;
  Status status;
  std::uint16_t speed = 0;  // the controller's slave speed (0: stopped)
  std::uint8_t alarm = 0;
  Ticket ticket = 0;
  std::vector<Bytes> sent;
};

TEST(Fdc1Contract, VerdictsOnWhatComesBack) {
  Hand h;
  const Bytes status = encode_status(Status{false, 0, 0, 0});
  EXPECT_EQ(h.d->on_receive(ByteView(status).first(5), h.now).kind, RxKind::incomplete);
  EXPECT_EQ(h.d->on_receive(status, h.now).kind, RxKind::frame);  // streamed, not awaited
  EXPECT_EQ(h.d->on_receive(status, h.now).consumed, kStatusSize);
  EXPECT_TRUE(h.d->common().ready);
  // A programming echo nobody awaits: a good frame, not ours to apply.
  const Bytes echo = encode_echo(Program{2000, 3000, 0, 2, {}});
  EXPECT_EQ(h.d->on_receive(echo, h.now).kind, RxKind::foreign);
  EXPECT_EQ(h.d->on_receive(echo, h.now).consumed, kProgramSize);
  // What the codec rejects: a bad checksum is counted as one, anything else skipped as noise. (An
  // OFF frame with alarm 48: no 1B inside it to resynchronise on.)
  Bytes bad = encode_status(Status{false, 0, 48, 1220});
  bad.back() ^= 1;
  EXPECT_EQ(h.d->on_receive(bad, h.now).kind, RxKind::bad_checksum);
  EXPECT_EQ(h.d->on_receive(bad, h.now).consumed, kStatusSize);
  const Bytes noise = {0x00, 0xFF, 0x1B, 0x4C};
  EXPECT_EQ(h.d->on_receive(noise, h.now).kind, RxKind::noise);
  EXPECT_EQ(h.d->on_receive(noise, h.now).consumed, 2u);  // up to the next 1B
  EXPECT_EQ(h.d->points().size(), h.d->values().size());
}

TEST(Fdc1Contract, EveryVerdictButIncompleteConsumes) {
  Hand h;
  Bytes junk;
  for (int i = 0; i < 300; ++i) junk.push_back(static_cast<std::uint8_t>((i * 37 + 11) % 256));
  junk.insert(junk.end(), {0x1B, 0x4C, 0x1B, 0x50, 0x1B});
  std::size_t at = 0;
  while (at < junk.size()) {
    const RxVerdict v = h.d->on_receive(ByteView(junk).subspan(at), h.now);
    if (v.kind == RxKind::incomplete) break;
    ASSERT_GT(v.consumed, 0u);
    at += v.consumed;
  }
  EXPECT_GE(at, 290u);
}

TEST(Fdc1Contract, WakesForTheStartUpTheRefreshAndTheConfirmDeadline) {
  Hand h;
  EXPECT_EQ(h.d->wake_at(), TimePoint::max());  // nothing to send before the stream
  EXPECT_FALSE(h.d->next_exchange(h.now).has_value());
  h.step();  // heard: the start-up stop went out
  ASSERT_EQ(h.sent.size(), 1u);
  EXPECT_GT(h.d->wake_at(), h.now + 29s);
  EXPECT_LE(h.d->wake_at(), h.now + 30s);  // refresh_s
  ASSERT_EQ(h.apply(WriteOp::of_setpoint(2000)), WriteStatus::done);
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::run_forward)), WriteStatus::pending);
  EXPECT_LE(h.d->wake_at(), h.now);  // the run frame is due at once
  const auto ex = h.d->next_exchange(h.now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->reply, ReplyMode::none);      // INPUT, Programming speed: never acknowledged
  EXPECT_EQ(h.d->wake_at(), h.now + 5000ms);  // the confirm deadline comes before the refresh
  std::vector<Completion> out;
  (void)h.d->next_exchange(h.now + 5000ms);
  h.d->take_completions(out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].result, WriteResult::no_response);
  EXPECT_EQ(h.d->common().command, Command::stop);
}

// The states a request may find the driver in.
enum class State { not_heard, stopped, stored, running, alarm_stopped, alarm_running, monitor };

void bring(Hand& h, State s) {
  if (s == State::not_heard) return;
  h.step();
  if (s == State::stopped || s == State::monitor) return;
  if (s == State::alarm_stopped) {
    h.alarm = 48;
    h.step();
    return;
  }
  ASSERT_EQ(h.apply(WriteOp::of_setpoint(2000)), WriteStatus::done);
  if (s == State::stored) return;
  ASSERT_EQ(h.apply(WriteOp::of_command(Command::run_forward)), WriteStatus::pending);
  ASSERT_EQ(h.settle(h.ticket), WriteResult::ok);
  ASSERT_EQ(h.d->common().command, Command::run_forward);
  if (s == State::running) return;
  h.alarm = 64;  // motor overload: the controller stops and will retry
  h.step();
}

const State kStates[] = {State::not_heard,     State::stopped,       State::stored, State::running,
                         State::alarm_stopped, State::alarm_running, State::monitor};

test::OptionText options_in(State s) {
  return s == State::monitor ? test::OptionText{} : kSlave;
}

std::vector<std::vector<WriteOp>> speed_requests() {
  std::vector<std::vector<WriteOp>> out;
  const std::optional<std::int32_t> setpoints[] = {std::nullopt, 0, 1499, 1500, 2000, 3500, 3501};
  for (const auto& rpm : setpoints) {
    std::vector<WriteOp> base;
    if (rpm) base.push_back(WriteOp::of_setpoint(*rpm));
    if (!base.empty()) out.push_back(base);
    for (const Command c : kAllCommands) {
      auto r = base;
      r.push_back(WriteOp::of_command(c));
      out.push_back(r);
    }
  }
  out.push_back({WriteOp::of_point(pt::motor_on, Value{std::int64_t{1}})});
  out.push_back({WriteOp::of_point(pt::prog_commit, Value{std::int64_t{1}})});
  return out;
}

WriteCheck as_check(WriteStatus s) {
  return s == WriteStatus::invalid_value ? WriteCheck::invalid_value : WriteCheck::refused;
}

std::string describe(const std::vector<WriteOp>& request) {
  std::string out;
  for (const WriteOp& op : request) {
    switch (op.target) {
      case WriteOp::Target::setpoint:
        out += "setpoint " + std::to_string(op.rpm) + "; ";
        break;
      case WriteOp::Target::command:
        out += std::string(to_string(op.command)) + "; ";
        break;
      case WriteOp::Target::point:
        out += "point " + std::to_string(op.point) + " = " + std::to_string(as_double(op.value)) +
               "; ";
        break;
    }
  }
  return out;
}

// Applies `request` as the gateway does, a part once the one before it settled, and says what
// check() should have answered. Nothing when the controller refused a part from the stream (an
// alarm): a verdict no driver can give in advance, after which the later parts are never applied.
std::optional<WriteCheck> applied(Hand& h, const std::vector<WriteOp>& request) {
  for (const WriteOp& op : request) {
    const WriteStatus st = h.apply(op);
    if (st == WriteStatus::invalid_value || st == WriteStatus::refused) return as_check(st);
    if (st == WriteStatus::pending) {
      const auto r = h.settle(h.ticket);
      EXPECT_TRUE(r.has_value()) << "never settled";
      if (r != WriteResult::ok) return std::nullopt;
    }
  }
  return WriteCheck::ok;
}

TEST(Fdc1Contract, CheckAcceptsARequestExactlyWhenApplyTakesItsPartsInOrder) {
  int compared = 0;
  for (const State s : kStates) {
    for (const auto& request : speed_requests()) {
      SCOPED_TRACE(testing::Message()
                   << "state " << static_cast<int>(s) << ": " << describe(request));
      Hand h(options_in(s));
      bring(h, s);
      const WriteCheck judged = h.d->check(request);
      const auto taken = applied(h, request);
      if (taken) {
        EXPECT_EQ(judged, *taken);
        ++compared;
      } else {
        // Only an alarm refuses what the driver took.
        EXPECT_TRUE(s == State::alarm_stopped || s == State::alarm_running);
      }
    }
  }
  EXPECT_GT(compared, 250);  // of 301
}

// Programming requests, as `drivegate action` makes them one part at a time or a PLC in one.
std::vector<std::vector<WriteOp>> program_requests() {
  const auto field = [](std::size_t point, double v) { return WriteOp::of_point(point, Value{v}); };
  const WriteOp commit = WriteOp::of_point(pt::prog_commit, Value{std::int64_t{1}});
  const std::vector<WriteOp> standard = {
      field(pt::prog_min_rpm, 2000),    field(pt::prog_max_rpm, 3000),
      field(pt::prog_mode, 2),          field(pt::prog_cut_out_12v, 10.5),
      field(pt::prog_cut_in_12v, 12.5), field(pt::prog_cut_out_24v, 21),
      field(pt::prog_cut_in_24v, 25),   field(pt::prog_cut_out_42v, 36),
      field(pt::prog_cut_in_42v, 44)};
  std::vector<std::vector<WriteOp>> out;
  out.push_back({commit});
  out.push_back({commit, commit});
  out.push_back({field(pt::prog_cut_out_12v, 13), commit});  // above cut-in: invalid
  out.push_back({field(pt::prog_cut_out_12v, 10.5), commit});
  out.push_back({field(pt::prog_mode, 34), commit});  // special: its fields missing
  out.push_back({field(pt::prog_min_rpm, 1499)});     // outside the point's limits
  out.push_back({field(pt::prog_mode, 2), field(pt::prog_mode, 1), commit});
  auto whole = standard;
  whole.push_back(commit);
  out.push_back(whole);
  auto broken = standard;
  broken.push_back(field(pt::prog_cut_in_42v, 46));
  broken.push_back(commit);
  out.push_back(broken);
  out.push_back({field(pt::prog_status, 0)});
  out.push_back({WriteOp::of_setpoint(2000), field(pt::prog_min_rpm, 2000), commit});
  return out;
}

enum class Fields { none, valid, invalid };

void fill(Hand& h, Fields f) {
  if (f == Fields::none) return;
  const std::pair<std::size_t, double> fields[] = {
      {pt::prog_min_rpm, 2000},     {pt::prog_max_rpm, 3000},    {pt::prog_mode, 2},
      {pt::prog_cut_out_12v, 10.5}, {pt::prog_cut_in_12v, 12.5}, {pt::prog_cut_out_24v, 21},
      {pt::prog_cut_in_24v, 25},    {pt::prog_cut_out_42v, 36},  {pt::prog_cut_in_42v, 44}};
  for (const auto& [point, v] : fields) {
    ASSERT_EQ(h.apply(WriteOp::of_point(point, Value{v})), WriteStatus::done);
  }
  if (f == Fields::invalid) {
    ASSERT_EQ(h.apply(WriteOp::of_point(pt::prog_cut_in_24v, Value{33.0})), WriteStatus::done);
  }
}

TEST(Fdc1Contract, CheckJudgesAProgrammingRequestAsApplyTakesIt) {
  for (const bool heard : {false, true}) {
    for (const Fields f : {Fields::none, Fields::valid, Fields::invalid}) {
      for (const auto& request : program_requests()) {
        SCOPED_TRACE(testing::Message() << (heard ? "heard" : "not heard") << ", fields "
                                        << static_cast<int>(f) << ": " << describe(request));
        Hand h(kSlave, /*maintenance=*/true);
        if (heard) h.step();
        fill(h, f);
        const WriteCheck judged = h.d->check(request);
        EXPECT_EQ(std::optional<WriteCheck>(judged), applied(h, request));
      }
    }
  }
}

TEST(Fdc1Contract, CheckHasNoSideEffects) {
  for (const State s : kStates) {
    SCOPED_TRACE(static_cast<int>(s));
    Hand judged(options_in(s), true);
    Hand untouched(options_in(s), true);
    bring(judged, s);
    bring(untouched, s);
    fill(judged, Fields::valid);
    fill(untouched, Fields::valid);
    for (const auto& request : speed_requests()) (void)judged.d->check(request);
    for (const auto& request : program_requests()) (void)judged.d->check(request);
    std::vector<Completion> none;
    judged.d->take_completions(none);
    EXPECT_TRUE(none.empty());
    const CommonState& a = judged.d->common();
    const CommonState& b = untouched.d->common();
    EXPECT_EQ(a.command, b.command);
    EXPECT_EQ(a.setpoint_rpm, b.setpoint_rpm);
    EXPECT_EQ(a.running, b.running);
    EXPECT_EQ(a.ready, b.ready);
    EXPECT_EQ(judged.d->values(), untouched.d->values());
    EXPECT_EQ(judged.d->wake_at(), untouched.d->wake_at());
    // And the line carries the same from here on.
    for (int i = 0; i < 80; ++i) {
      judged.step();
      untouched.step();
    }
    EXPECT_EQ(judged.sent, untouched.sent);
  }
}

}  // namespace
}  // namespace drivegate::fdc1
