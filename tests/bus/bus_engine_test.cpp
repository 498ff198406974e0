// The bus engine on simulated time (tests/support/bus_rig.h) with a tiny request / reply
// protocol of the test's own: polls at the poll interval, resends, the time budget, back-off of a
// silent device, comm_lost, writes and polls sharing the line fairly, late replies kept out of
// later exchanges, data age, and the one-wire echo, asserted on the frames the line carried and
// the registers a PLC reads.
#include <gtest/gtest.h>

#include <algorithm>
#include <deque>

#include "bus_rig.h"
#include "fake_adapter.h"

namespace drivegate {
namespace {

using namespace std::chrono_literals;

// The test protocol: poll A0 addr -> B0 addr value; command C0 addr cmd -> D0 addr cmd;
// a NACK is EE addr 00; a damaged reply is BE addr xx (a "bad checksum").
constexpr std::uint8_t kPoll = 0xA0, kPollReply = 0xB0, kCommand = 0xC0, kCommandReply = 0xD0,
                       kNack = 0xEE, kDamaged = 0xBE;

class PingDriver final : public Driver {
 public:
  PingDriver(std::uint8_t address, Millis poll, Millis timeout = Millis(50))
      : address_(address), poll_(poll), timeout_(timeout) {
    points_.push_back(input_point("value", PointType::u16, "", "the polled value"));
    values_.resize(1);
  }
  DriverTraits traits() const override { return {Millis(1000), Millis(3000), Millis(2)}; }
  const std::vector<PointSpec>& points() const override { return points_; }
  const std::vector<Value>& values() const override { return values_; }
  const CommonState& common() const override { return common_; }
  std::optional<Exchange> next_exchange(TimePoint now) override {
    Exchange ex;
    ex.timeout = timeout_;
    ex.attempts = 3;
    if (pending_ && !pending_sent_) {
      pending_sent_ = true;
      ex.frame = {kCommand, address_, static_cast<std::uint8_t>(pending_command_)};
      return ex;
    }
    if (now < next_poll_) return std::nullopt;
    next_poll_ = now + poll_;
    ex.frame = {kPoll, address_};
    return ex;
  }
  TimePoint wake_at() const override {
    return pending_ && !pending_sent_ ? TimePoint{} : next_poll_;
  }
  RxVerdict on_receive(ByteView rx, TimePoint) override {
    if (rx.size() < 3) return {RxKind::incomplete, 0};
    if (rx[1] != address_) return {RxKind::foreign, 3};
    switch (rx[0]) {
      case kPollReply:
        common_.ready = true;
        values_[0] = std::int64_t{rx[2]};
        return {RxKind::reply, 3};
      case kCommandReply:
        // The command's echo: it says the drive took it, nothing about its state.
        if (!pending_ || !pending_sent_ || rx[2] != static_cast<std::uint8_t>(pending_command_)) {
          return {RxKind::foreign, 3};
        }
        common_.command = static_cast<Command>(rx[2]);
        completions_.push_back({*pending_, WriteResult::ok});
        pending_.reset();
        return {RxKind::ack, 3};
      case kNack:
        return {RxKind::nack, 3};
      case kDamaged:
        return {RxKind::bad_checksum, 3};
      default:
        return {RxKind::noise, 1};
    }
  }
  void on_no_reply(TimePoint) override {
    if (pending_ && pending_sent_) {
      completions_.push_back({*pending_, WriteResult::no_response});
      pending_.reset();
    }
  }
  void on_comm_lost(TimePoint) override { common_.ready = false; }
  WriteCheck check(std::span<const WriteOp>) const override { return WriteCheck::ok; }
  WriteStatus apply(const WriteOp& op, Ticket t, TimePoint) override {
    if (op.target != WriteOp::Target::command) return WriteStatus::done;
    pending_ = t;
    pending_sent_ = false;
    pending_command_ = op.command;
    return WriteStatus::pending;
  }
  void take_completions(std::vector<Completion>& out) override {
    out.insert(out.end(), completions_.begin(), completions_.end());
    completions_.clear();
  }

 private:
  std::uint8_t address_;
  Millis poll_;
  Millis timeout_;
  TimePoint next_poll_{};
  std::vector<PointSpec> points_;
  std::vector<Value> values_;
  CommonState common_;
  std::optional<Ticket> pending_;
  bool pending_sent_ = false;
  Command pending_command_ = Command::stop;
  std::vector<Completion> completions_;
};

// The device side: answers its address; silent, NACKing or damaging on request, answering only
// commands (its polls NACKed), answering `lateness` late (from its 10 ms ticks), or answering every
// other request it hears.
class PingSim final : public Simulator {
 public:
  enum class Mode { answer, silent, nack, damage, commands_only, late, every_other };
  explicit PingSim(std::uint8_t address) : address_(address) {}
  Bytes on_receive(ByteView rx, TimePoint now) override {
    if (rx.size() < 2 || rx[1] != address_ || mode == Mode::silent) return {};
    if (mode == Mode::every_other && (heard_++ % 2) == 0) return {};
    if (mode == Mode::nack) return {kNack, address_, 0};
    if (mode == Mode::damage) return {kDamaged, address_, 0};
    if (rx[0] == kCommand && rx.size() == 3) return {kCommandReply, address_, rx[2]};
    if (mode == Mode::commands_only) return {kNack, address_, 0};
    if (mode == Mode::late) {
      late_.push_back({now + lateness, {kPollReply, address_, value}});
      return {};
    }
    return {kPollReply, address_, value};
  }
  Bytes on_tick(TimePoint now) override {
    Bytes out;
    while (!late_.empty() && now >= late_.front().first) {
      out.insert(out.end(), late_.front().second.begin(), late_.front().second.end());
      late_.pop_front();
    }
    return out;
  }
  std::string control(std::string_view, TimePoint) override { return {}; }
  Mode mode = Mode::answer;
  std::uint8_t value = 42;
  Millis lateness{70};

 private:
  std::uint8_t address_;
  std::uint64_t heard_ = 0;
  std::deque<std::pair<TimePoint, Bytes>> late_;  // every request's answer, in order
};

BusConfig line(bool echo = false) {
  BusConfig b;
  b.name = "test";
  b.baud = 9600;  // 8N1: 10 bits a character, 1.0417 ms
  b.echo = echo;
  return b;
}

struct Bench {
  explicit Bench(BusConfig config = line()) : rig(test::kFakeAdapter, std::move(config)) {}
  Device& add(std::uint8_t address, Millis poll = 100ms, Millis budget = 1000ms,
              Millis timeout = 50ms) {
    DeviceConfig c = rig.device_config("dev" + std::to_string(address), address);
    c.poll_interval = poll;
    c.budget = budget;
    c.backoff_max = 2000ms;
    auto& d = rig.add_device(c, std::make_unique<PingDriver>(address, poll, timeout));
    auto sim = std::make_unique<PingSim>(address);
    sims.push_back(sim.get());
    rig.add_simulator(std::move(sim));
    return d;
  }
  // Frames sent to `address` with `kind`, and when.
  std::vector<TimePoint> sent(std::uint8_t kind, std::uint8_t address, TimePoint from = {}) {
    std::vector<TimePoint> out;
    for (const auto& f : rig.sent()) {
      if (f.at >= from && f.bytes.size() >= 2 && f.bytes[0] == kind && f.bytes[1] == address) {
        out.push_back(f.at);
      }
    }
    return out;
  }
  test::BusRig rig;
  std::vector<PingSim*> sims;
};

TEST(BusEngine, PollsAtThePollIntervalAndPublishesTheValue) {
  Bench b;
  Device& d = b.add(1);
  b.rig.start();
  b.rig.run_for(1020ms);  // the last poll's answer is in too
  const auto polls = b.sent(kPoll, 1);
  ASSERT_GE(polls.size(), 9u);
  // The first waits for the 2 ms inter-frame gap after the line opened; each next poll is due
  // 100 ms after the one before was asked for.
  EXPECT_EQ(polls[1] - polls[0], 98ms);
  for (std::size_t i = 2; i < polls.size(); ++i) EXPECT_EQ(polls[i] - polls[i - 1], 100ms);
  EXPECT_TRUE(d.online());
  EXPECT_EQ(b.rig.read(d, "value"), std::vector<std::uint16_t>{42});
  EXPECT_EQ(b.rig.read(d, Table::input, 9, 2)[1], polls.size());  // frames_good
  EXPECT_EQ(b.rig.counters().exchanges, polls.size());
}

TEST(BusEngine, ASilentReplyIsResentAfterItsTimeoutCountingTheWire) {
  Bench b;
  Device& d = b.add(1);
  b.rig.start();
  b.rig.run_for(50ms);
  b.sims[0]->mode = PingSim::Mode::silent;
  const TimePoint from = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.rig.read(d, Table::input, 13, 2)[1] == 3; }, 1s));
  ASSERT_TRUE(b.rig.run_until([&] { return b.sent(kPoll, 1, from).size() == 4; }, 1s));
  const auto polls = b.sent(kPoll, 1, from);
  // Three attempts. 2 bytes at 9600 8N1 leave the UART in 2.08 ms (counted as 2): the 50 ms wait
  // counts from then, then the line is kept quiet for the guard time (the timeout again) before
  // the identical frame goes again.
  EXPECT_EQ(polls[1] - polls[0], 102ms);
  EXPECT_EQ(polls[2] - polls[1], 102ms);
  // The device is alone on its line: the turn's timeouts cost nobody else, so its next poll
  // turn comes with no pause for the line time it held (bus_engine.h, "Sick devices").
  EXPECT_EQ(polls[3] - polls[2], 102ms);
  EXPECT_EQ(b.rig.read(d, Table::input, 15, 2)[1], 2);  // retries: 3 attempts, 2 of them resends
}

// Behind a serial device server the reply also crosses the network: network_delay_ms is added to
// every reply timeout, and the budget's count of attempts knows it.
TEST(BusEngine, ANetworkDelayLengthensEveryReplyTimeout) {
  BusConfig config = line();
  config.network_delay = 30ms;
  Bench b(config);
  Device& d = b.add(1);
  b.rig.start();
  b.rig.run_for(50ms);
  b.sims[0]->mode = PingSim::Mode::silent;
  const TimePoint from = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return b.rig.read(d, Table::input, 13, 2)[1] == 3; }, 1s));
  const auto polls = b.sent(kPoll, 1, from);
  ASSERT_GE(polls.size(), 3u);
  // 2 ms on the wire + 50 ms timeout + 30 ms network, and the guard time: 80 ms again.
  EXPECT_EQ(polls[1] - polls[0], 162ms);
  EXPECT_EQ(polls[2] - polls[1], 162ms);
}

TEST(BusEngine, NacksAndDamagedRepliesAreResentAtOnceWithoutBackOff) {
  Bench b;
  Device& d = b.add(1);
  b.rig.start();
  b.rig.run_for(50ms);
  b.sims[0]->mode = PingSim::Mode::nack;
  b.rig.run_for(300ms);
  b.sims[0]->mode = PingSim::Mode::damage;
  b.rig.run_for(300ms);
  EXPECT_GT(b.rig.read(d, Table::input, 17, 2)[1], 0);  // nacks
  EXPECT_GT(b.rig.read(d, Table::input, 11, 2)[1], 0);  // bad checksums
  EXPECT_EQ(b.rig.read(d, Table::input, 13, 2)[1], 0);  // no timeouts: it answered
  // It answers, garbled: its poll rate stays (no back-off), 3 attempts every 100 ms.
  EXPECT_GE(b.sent(kPoll, 1, b.rig.now() - 300ms).size(), 9u);
}

TEST(BusEngine, ASilentDeviceGoesCommLostAndIsBackedOffWhileTheOtherKeepsItsRate) {
  Bench b;
  Device& alive = b.add(1, 100ms);
  Device& dead = b.add(2, 100ms, 200ms);
  b.rig.start();
  b.rig.run_for(500ms);
  b.sims[1]->mode = PingSim::Mode::silent;
  b.rig.run_for(1200ms);
  EXPECT_TRUE(dead.comm_lost());
  EXPECT_FALSE(alive.comm_lost());
  const auto lost = b.rig.read(dead, Table::input, 0, 2);
  EXPECT_EQ(lost[0] & (1u << 4), 1u << 4);  // status comm_lost
  EXPECT_EQ(lost[1], static_cast<std::uint16_t>(Fault::comm_lost));
  const TimePoint from = b.rig.now();
  b.rig.run_for(10s);
  // The live device keeps its 100 ms polls but for the dead one's probes, which its 200 ms budget
  // holds to one attempt of 102 ms (timeout and guard) every 2 s; the dead one is probed, backed
  // off to 2 s.
  EXPECT_GE(b.sent(kPoll, 1, from).size(), 90u);
  const auto probes = b.sent(kPoll, 2, from);
  EXPECT_LE(probes.size(), 6u);  // at most 6 turns of one attempt in 10 s
  EXPECT_GE(probes.size(), 4u);
  b.sims[1]->mode = PingSim::Mode::answer;
  ASSERT_TRUE(b.rig.run_until([&] { return !dead.comm_lost(); }, 3s));
}

TEST(BusEngine, TheBudgetCapsTheAttemptsOfOneTurn) {
  Bench b;
  Device& d = b.add(1, 100ms, 150ms);  // room for one attempt of 50 ms and its 50 ms guard only
  b.rig.start();
  b.rig.run_for(50ms);
  b.sims[0]->mode = PingSim::Mode::silent;
  b.rig.run_for(500ms);
  EXPECT_EQ(b.rig.read(d, Table::input, 15, 2)[1], 0);  // never a resend
  EXPECT_GT(b.rig.read(d, Table::input, 13, 2)[1], 0);
}

TEST(BusEngine, AWriteGoesOutAtTheNextTurnAndIsAnsweredOnceConfirmed) {
  Bench b;
  Device& d1 = b.add(1, 20ms);
  b.add(2, 20ms);
  b.rig.start();
  b.rig.run_for(200ms);
  const auto w = b.rig.write(d1, Table::holding, 0, {1});
  EXPECT_FALSE(w->settled());
  const TimePoint asked = b.rig.now();
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  const auto commands = b.sent(kCommand, 1);
  ASSERT_EQ(commands.size(), 1u);
  // Sent as soon as the exchange on the line when it was asked ended (one poll at most).
  EXPECT_LE(commands[0] - asked, 10ms);
  EXPECT_EQ(b.rig.read(d1, Table::holding, 0, 1), std::vector<std::uint16_t>{1});
}

TEST(BusEngine, AWriteToADeviceThatStopsAnsweringFailsWith0x0B) {
  Bench b;
  Device& d = b.add(1);
  b.rig.start();
  b.rig.run_for(200ms);
  b.sims[0]->mode = PingSim::Mode::silent;
  EXPECT_EQ(b.rig.write_and_wait(d, Table::holding, 0, {1}), Outcome::no_response);
  b.rig.run_for(2s);
  EXPECT_TRUE(d.comm_lost());
  // Now refused at once, without a frame.
  const auto before = b.sent(kCommand, 1).size();
  EXPECT_EQ(b.rig.write(d, Table::holding, 0, {1})->result, Outcome::no_response);
  EXPECT_EQ(b.sent(kCommand, 1).size(), before);
}

TEST(BusEngine, OnAOneWireLineTheEchoIsCheckedAndDropped) {
  Bench b(line(/*echo=*/true));
  Device& d = b.add(1);
  b.rig.start();
  b.rig.run_for(1000ms);
  EXPECT_TRUE(d.online());
  EXPECT_EQ(b.rig.counters().echo_errors, 0u);
  EXPECT_EQ(b.rig.read(d, Table::input, 13, 2)[1], 0);  // the echo is not mistaken for a reply
  // A collision: the echo comes back different.
  b.rig.line().connected = false;  // nothing reaches the device...
  b.rig.run_for(300ms);
  EXPECT_EQ(b.rig.counters().echo_errors, 0u);  // ...but the echo still comes back intact
  b.rig.line().connected = true;
}

TEST(BusEngine, ARepliesForAnotherAddressAreCountedForeign) {
  Bench b;
  Device& d = b.add(1);
  b.rig.start();
  b.rig.line().device_filter = [](Bytes bytes) {
    if (bytes.size() == 3) bytes[1] = 9;  // someone else's reply
    return bytes;
  };
  b.rig.run_for(300ms);
  EXPECT_GT(b.rig.read(d, Table::input, 29, 2)[1], 0);  // foreign_frames
  EXPECT_FALSE(d.online());
}

TEST(BusEngine, ThePortFailingFailsTheExchangeAndReopeningCounts) {
  Bench b;
  Device& d = b.add(1);
  b.rig.start();
  b.rig.run_for(200ms);
  b.rig.line_down();
  const auto before = b.rig.sent().size();
  b.rig.run_for(500ms);
  EXPECT_EQ(b.rig.sent().size(), before);  // nothing sent on a closed line
  b.rig.line_up();
  b.rig.run_for(200ms);
  EXPECT_GT(b.rig.sent().size(), before);
  EXPECT_EQ(b.rig.read(d, Table::input, 27, 2)[1], 1);  // bus_reopens
}

// --- late replies (docs/safety.md, "Late replies") ---------------------------------------------

// A device that answers 70 ms after each request, its timeout being 50 ms: every reply arrives in
// the guard time after its timeout, is dropped and counted late, and none is ever taken for the
// answer to the resend or to the next poll. With no good frame, the device goes comm_lost.
TEST(BusEngine, AReplyAfterItsTimeoutIsDroppedAsLateNeverCreditedToALaterRequest) {
  Bench b;
  Device& d = b.add(1);
  b.rig.line().turnaround = 70ms;
  b.sims[0]->value = 7;
  b.rig.start();
  b.rig.run_for(3s);
  EXPECT_TRUE(d.comm_lost());
  EXPECT_FALSE(d.online());
  EXPECT_EQ(b.rig.read(d, Table::input, 9, 2)[1], 0);                // frames_good: none
  EXPECT_NE(b.rig.read(d, "value"), std::vector<std::uint16_t>{7});  // never taken
  EXPECT_GT(d.line().counters.late_bytes, 0u);
  EXPECT_EQ(d.line().counters.late_bytes, b.rig.counters().late_bytes);
  // Nothing was sent while a reply was still on its way: every poll went at least one timeout
  // plus one guard after the one before.
  const auto polls = b.sent(kPoll, 1);
  for (std::size_t i = 1; i < polls.size(); ++i) EXPECT_GE(polls[i] - polls[i - 1], 100ms);
  // Answering in time again, it is back.
  b.rig.line().turnaround = 5ms;
  ASSERT_TRUE(b.rig.run_until([&] { return d.online(); }, 3s));
  EXPECT_EQ(b.rig.read(d, "value"), std::vector<std::uint16_t>{7});
}

// Two devices on a line, one of them late: its late replies never land in its neighbour's
// exchange, and the neighbour keeps being polled and answering.
TEST(BusEngine, ALateDeviceNeverAnswersForItsNeighbour) {
  Bench b;
  Device& late = b.add(1);
  Device& good = b.add(2);
  b.rig.start();
  b.rig.run_for(300ms);
  b.sims[0]->mode = PingSim::Mode::late;
  const TimePoint from = b.rig.now();
  b.rig.run_for(3s);
  ASSERT_TRUE(late.comm_lost());
  EXPECT_TRUE(good.online());
  EXPECT_GT(late.line().counters.late_bytes, 0u);
  EXPECT_EQ(b.rig.read(good, Table::input, 29, 2)[1], 0);  // not one foreign frame in its turns
  EXPECT_GE(b.sent(kPoll, 2, from).size(), 15u);           // half its rate at least
}

// --- fair line time (docs/safety.md, "Fair line time") -----------------------------------------

// A sick neighbour costs its own line time: beside a device that is silent, answers 1.1 s late or
// answers every other request (each turn of it then runs into 150 ms timeouts and their guard
// times), a healthy device polled every 100 ms keeps at least half of its 100 good frames in 10 s,
// and the sick one is still asked.
void healthy_keeps_half_its_rate(PingSim::Mode sickness) {
  Bench b;
  Device& healthy = b.add(1, 100ms);
  b.add(2, 100ms, 1000ms, 150ms);  // the sick one
  b.sims[1]->lateness = 1100ms;
  b.rig.start();
  b.rig.run_for(500ms);
  b.sims[1]->mode = sickness;
  const auto frames = [&](Device& d) {
    const auto r = b.rig.read(d, Table::input, 9, 2);
    return (std::uint32_t{r[0]} << 16) | r[1];
  };
  const std::uint32_t before = frames(healthy);
  const TimePoint from = b.rig.now();
  b.rig.run_for(10s);
  EXPECT_GE(frames(healthy) - before, 50u);
  EXPECT_FALSE(healthy.comm_lost());
  EXPECT_GE(b.sent(kPoll, 2, from).size(), 3u);  // backed off, never forgotten
}

TEST(BusEngine, ASilentNeighbourLeavesAHealthyDeviceHalfItsRate) {
  healthy_keeps_half_its_rate(PingSim::Mode::silent);
}

TEST(BusEngine, ANeighbourAnsweringLateLeavesAHealthyDeviceHalfItsRate) {
  healthy_keeps_half_its_rate(PingSim::Mode::late);
}

TEST(BusEngine, ANeighbourAnsweringEveryOtherRequestLeavesAHealthyDeviceHalfItsRate) {
  healthy_keeps_half_its_rate(PingSim::Mode::every_other);
}

// A client that keeps writing to device 1 (each write followed by the next as soon as it is
// answered) never stops the line's polls: device 2 keeps its poll rate to within half, device 1
// itself is still polled (a value changed at the drive is seen), and neither goes comm_lost.
TEST(BusEngine, AWriteStormLeavesEveryDevicePolled) {
  Bench b;
  Device& written = b.add(1, 100ms);
  Device& neighbour = b.add(2, 100ms);
  b.rig.start();
  b.rig.run_for(300ms);
  const TimePoint from = b.rig.now();
  int answered = 0;
  std::function<void()> next;
  std::vector<std::shared_ptr<test::WriteOutcome>> outstanding;
  for (int i = 0; i < 2; ++i) outstanding.push_back(b.rig.write(written, Table::holding, 0, {1}));
  b.sims[0]->value = 99;
  const TimePoint end = from + 5s;
  while (b.rig.now() < end) {
    b.rig.run_for(1ms);
    for (auto& w : outstanding) {
      if (!w->settled()) continue;
      EXPECT_EQ(w->result, Outcome::ok);
      ++answered;
      w = b.rig.write(written, Table::holding, 0, {static_cast<std::uint16_t>(1 + answered % 2)});
    }
    ASSERT_FALSE(neighbour.comm_lost());
    ASSERT_FALSE(written.comm_lost());
  }
  EXPECT_GT(answered, 50);  // the storm really went on
  // At least half of the 50 polls 5 s at 100 ms make, for both.
  EXPECT_GE(b.sent(kPoll, 2, from).size(), 25u);
  EXPECT_GE(b.sent(kPoll, 1, from).size(), 25u);
  EXPECT_EQ(b.rig.read(written, "value"), std::vector<std::uint16_t>{99});
}

// Writes wait in a short queue: past kMaxQueuedWrites the answer is 0x06 at once, not a timeout;
// a write equal to the one queued before it waits with it and is answered with it.
TEST(BusEngine, AFullWriteQueueAnswersBusyAtOnceAndEqualWritesCoalesce) {
  Bench b;
  Device& d = b.add(1, 100ms);
  b.rig.start();
  b.rig.run_for(200ms);
  std::vector<std::shared_ptr<test::WriteOutcome>> writes;
  for (std::uint16_t rpm = 1; rpm <= kMaxQueuedWrites; ++rpm) {
    writes.push_back(b.rig.write(d, Table::holding, 0, {static_cast<std::uint16_t>(rpm % 2 + 1)}));
  }
  const auto same =
      b.rig.write(d, Table::holding, 0, {static_cast<std::uint16_t>(kMaxQueuedWrites % 2 + 1)});
  EXPECT_FALSE(same->settled());  // coalesced with the last one: no place taken
  const auto busy = b.rig.write(d, Table::holding, 0, {4});  // reset_fault: queued like a run
  ASSERT_TRUE(busy->settled());
  EXPECT_EQ(busy->result, Outcome::busy);
  for (auto& w : writes) EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  EXPECT_EQ(b.rig.wait(same), Outcome::ok);
  EXPECT_EQ(d.write_stats().busy, 1u);
  EXPECT_EQ(d.write_stats().coalesced, 1u);
  // One frame per queued write, in the order asked; the coalesced one sent nothing of its own.
  EXPECT_EQ(b.sent(kCommand, 1).size(), kMaxQueuedWrites);
}

// A stop does not queue: it goes to the line at the next turn, and the queued writes that would
// run the motor after it are dropped, never sent (0x0B).
TEST(BusEngine, AStopOvertakesTheQueueAndDropsTheRunsQueuedBeforeIt) {
  Bench b;
  Device& d = b.add(1, 100ms);
  b.rig.start();
  b.rig.run_for(200ms);
  const auto first = b.rig.write(d, Table::holding, 0, {1});
  const auto second = b.rig.write(d, Table::holding, 0, {2});
  const auto stop = b.rig.write(d, Table::holding, 0, {0});
  EXPECT_EQ(b.rig.wait(stop), Outcome::ok);
  EXPECT_EQ(b.rig.wait(second), Outcome::no_response);
  b.rig.wait(first);
  b.rig.run_for(300ms);
  // Run reverse (2) never reached the line.
  for (const auto& f : b.rig.sent()) {
    EXPECT_FALSE(f.bytes.size() == 3 && f.bytes[0] == kCommand && f.bytes[2] == 2);
  }
  EXPECT_EQ(b.rig.read(d, Table::holding, 0, 1), std::vector<std::uint16_t>{0});
}

// --- data age (docs/safety.md, "Data age") ------------------------------------------------------

// A drive that acknowledges every command but whose polls fail: it answers (never comm_lost while
// commands flow), but data_age_ms counts from its last status, not from the echoes.
TEST(BusEngine, AWriteEchoDoesNotMakeTheDataFresh) {
  Bench b;
  Device& d = b.add(1, 100ms);
  b.rig.start();
  b.rig.run_for(300ms);
  b.sims[0]->mode = PingSim::Mode::commands_only;
  const TimePoint from = b.rig.now();
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(b.rig.write_and_wait(d, Table::holding, 0, {static_cast<std::uint16_t>(1 + i % 2)}),
              Outcome::ok);
    b.rig.run_for(40ms);
  }
  const auto age = b.rig.read(d, Table::input, 7, 2);
  const auto age_ms = (std::uint32_t{age[0]} << 16) | age[1];
  EXPECT_GE(age_ms, std::chrono::duration_cast<Millis>(b.rig.now() - from).count() - 100);
  EXPECT_GT(b.rig.read(d, Table::input, 9, 2)[1], 20);  // the echoes count as good frames
}

}  // namespace
}  // namespace drivegate
