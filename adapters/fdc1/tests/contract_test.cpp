// The driver alone, where the contract of include/drivegate/driver.h is about one call: the
// verdicts of on_receive(), check() judging a request with no side effects and exactly as apply()
// then takes its parts, and when the driver wants to be woken.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "adapter_factories.h"
#include "bench.h"
#include "codec.h"
#include "driver.h"
#include "driver_by_hand.h"
#include "points.h"
#include "write_contract.h"

namespace drivegate::fdc1 {
namespace {

// A driver from the adapter's own factory, and the controller played by hand: it streams
// `status` every 0.5 s, follows every speed frame (unless in alarm), and echoes programming frames.
struct Hand : test::DriverByHand {
  explicit Hand(const test::OptionText& options = kSlave, bool maintenance = false)
      : DriverByHand(test::make_driver(drivegate_adapter,
                                       {.options = options, .maintenance = maintenance})) {}

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
        EXPECT_EQ(d->on_receive(echo, now).kind, RxKind::ack);  // no status in an echo
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
  bool turn() override {
    step();
    return true;
  }

  Status status;
  std::uint16_t speed = 0;  // the controller's slave speed (0: stopped)
  std::uint8_t alarm = 0;
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

// Programming requests, as `drivegate action` makes them one part at a time or a PLC in one.
std::vector<test::Request> program_requests() {
  const auto field = [](std::size_t point, double v) { return WriteOp::of_point(point, Value{v}); };
  const WriteOp commit = WriteOp::of_point(pt::prog_commit, Value{std::int64_t{1}});
  const std::vector<WriteOp> standard = {
      field(pt::prog_min_rpm, 2000),    field(pt::prog_max_rpm, 3000),
      field(pt::prog_mode, 2),          field(pt::prog_cut_out_12v, 10.5),
      field(pt::prog_cut_in_12v, 12.5), field(pt::prog_cut_out_24v, 21),
      field(pt::prog_cut_in_24v, 25),   field(pt::prog_cut_out_42v, 36),
      field(pt::prog_cut_in_42v, 44)};
  std::vector<test::Request> out;
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
  ASSERT_TRUE(test::runs_forward(h));
  if (s == State::running) return;
  h.alarm = 64;  // motor overload: the controller stops and will retry
  h.step();
}

constexpr std::pair<State, std::string_view> kStates[] = {
    {State::not_heard, "not heard"},          {State::stopped, "stopped"},
    {State::stored, "setpoint stored"},       {State::running, "running"},
    {State::alarm_stopped, "alarm, stopped"}, {State::alarm_running, "alarm, running"},
    {State::monitor, "monitor only"}};

// Each state on a fresh driver; in maintenance mode with valid programming fields stored too.
std::vector<test::WriteState> states(bool programmed = false) {
  std::vector<test::WriteState> out;
  for (const auto& [state, name] : kStates) {
    const State s = state;  // a copy the lambda can hold
    const test::OptionText options = s == State::monitor ? test::OptionText{} : kSlave;
    out.push_back({std::string(name), [=] {
                     auto h = std::make_unique<Hand>(options, /*maintenance=*/programmed);
                     bring(*h, s);
                     if (programmed) fill(*h, Fields::valid);
                     return h;
                   }});
  }
  return out;
}

std::vector<test::Request> speed_requests() {
  auto out = test::command_requests({0, 1499, 1500, 2000, 3500, 3501});
  out.push_back({WriteOp::of_point(pt::motor_on, Value{std::int64_t{1}})});
  out.push_back({WriteOp::of_point(pt::prog_commit, Value{std::int64_t{1}})});
  return out;
}

// The controller refuses a part from the stream only in an alarm: a verdict no driver can give in
// advance, after which the later parts are never applied.
TEST(Fdc1Contract, CheckAcceptsARequestExactlyWhenApplyTakesItsPartsInOrder) {
  const auto tally = test::expect_check_is_apply(states(), speed_requests());
  for (const auto& ended : tally.ended_by_device) {
    EXPECT_TRUE(ended.state.starts_with("alarm")) << ended.state << ": " << ended.request;
  }
  EXPECT_GT(tally.compared, 250);  // of 301
}

TEST(Fdc1Contract, CheckJudgesAProgrammingRequestAsApplyTakesIt) {
  std::vector<test::WriteState> programming;
  for (const bool heard : {false, true}) {
    for (const auto& [fields, name] :
         {std::pair{Fields::none, "no fields"}, std::pair{Fields::valid, "valid fields"},
          std::pair{Fields::invalid, "invalid fields"}}) {
      const Fields f = fields;  // a copy the lambda can hold
      programming.push_back({std::string(heard ? "heard, " : "not heard, ") + name, [=] {
                               auto h = std::make_unique<Hand>(kSlave, /*maintenance=*/true);
                               if (heard) h->step();
                               fill(*h, f);
                               return h;
                             }});
    }
  }
  const auto tally = test::expect_check_is_apply(programming, program_requests());
  EXPECT_TRUE(tally.ended_by_device.empty());
}

TEST(Fdc1Contract, CheckHasNoSideEffects) {
  auto requests = speed_requests();
  for (auto& r : program_requests()) requests.push_back(std::move(r));
  test::expect_check_has_no_side_effects(states(/*programmed=*/true), requests, /*turns=*/80);
}

}  // namespace
}  // namespace drivegate::fdc1
