// The pass-through driver (adapters/modbus/passthrough.h): by hand, the exact frames it sends and
// what it makes of replies; then on the real bus engine with simulated time (bus_rig.h), a
// pass-through device beside a profile device on one line, forwarded requests answered with the
// slave's exact reply, and what a flood of them, a dead slave and an access level do.
#include "passthrough.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "common_block.h"
#include "line_timing.h"

namespace drivegate::modbus_device::modbus_passthrough_test {
namespace {

using namespace std::chrono_literals;

constexpr std::uint8_t kSlave = 9;
// 19200 baud, 8E1: 11 bits a character.
constexpr std::chrono::nanoseconds kCharTime(572917);

Bytes rtu(std::vector<std::uint8_t> pdu, std::uint8_t address = kSlave) {
  return encode(Framing::rtu, address, pdu);
}

class PassthroughByHand : public ::testing::Test {
 protected:
  PassthroughDriver d{kSlave, PassthroughSettings{}, kCharTime, 500ms};
  TimePoint now = TimePoint{} + 10s;

  std::vector<Completion> completions() {
    std::vector<Completion> out;
    d.take_completions(out);
    return out;
  }
};

// Application Protocol 6.3's example: read holding registers 108..110 (0x6B, 3), and its reply.
const Bytes kReadRequest = {0x03, 0x00, 0x6B, 0x00, 0x03};
const Bytes kReadReply = {0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64};

TEST_F(PassthroughByHand, ItForwardsThePduAsItIsAndAnswersWithTheSlavesExactReply) {
  EXPECT_TRUE(d.forwards());
  EXPECT_TRUE(d.points().empty());  // nothing of the slave is mapped
  const WriteOp op = WriteOp::of_forward(kReadRequest);
  ASSERT_EQ(d.check(std::span(&op, 1)), WriteCheck::ok);
  ASSERT_EQ(d.apply(op, 41, now), WriteStatus::pending);
  const auto ex = d.next_exchange(now);
  ASSERT_TRUE(ex);
  // Serial Line 2.5.1: address, PDU, CRC low byte first.
  EXPECT_EQ(ex->frame, (Bytes{0x09, 0x03, 0x00, 0x6B, 0x00, 0x03, 0x75, 0x5F}));
  EXPECT_EQ(ex->attempts, 1);  // the client's own retries decide: a write is never sent twice
  // The reply, split in two reads: nothing until it is whole.
  const Bytes reply = rtu(kReadReply);
  EXPECT_EQ(d.on_receive(ByteView(reply).first(4), now).kind, RxKind::incomplete);
  const RxVerdict v = d.on_receive(reply, now);
  EXPECT_EQ(v.kind, RxKind::ack);  // the gateway keeps nothing of it: no data age
  EXPECT_EQ(v.consumed, reply.size());
  const auto done = completions();
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].ticket, 41u);
  EXPECT_EQ(done[0].result, WriteResult::ok);
  EXPECT_EQ(done[0].reply, kReadReply);
  EXPECT_TRUE(d.common().ready);
}

TEST_F(PassthroughByHand, AnExceptionReplyIsTheAnswerAsItCame) {
  ASSERT_EQ(d.apply(WriteOp::of_forward({0x06, 0x00, 0x01, 0x00, 0x03}), 1, now),
            WriteStatus::pending);
  ASSERT_TRUE(d.next_exchange(now));
  // Application Protocol 7: function | 0x80, code 02.
  EXPECT_EQ(d.on_receive(rtu({0x86, 0x02}), now).kind, RxKind::ack);
  const auto done = completions();
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].result, WriteResult::ok);
  EXPECT_EQ(done[0].reply, (Bytes{0x86, 0x02}));
}

TEST_F(PassthroughByHand, AnotherSlavesOrAnotherFunctionsFrameIsNotTheReply) {
  ASSERT_EQ(d.apply(WriteOp::of_forward(kReadRequest), 1, now), WriteStatus::pending);
  ASSERT_TRUE(d.next_exchange(now));
  EXPECT_EQ(d.on_receive(rtu(kReadReply, 10), now).kind, RxKind::foreign);
  EXPECT_EQ(d.on_receive(rtu({0x04, 0x02, 0x00, 0x01}), now).kind, RxKind::foreign);
  EXPECT_TRUE(completions().empty());
  d.on_no_reply(now);
  const auto done = completions();
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].result, WriteResult::no_response);  // 0x0B at the client
  EXPECT_TRUE(done[0].reply.empty());
}

// The gateway hands the driver no function of unknown length (forward_access.h); the driver
// itself sends what it is handed, and the reply of a function the codec does not know ends where
// its CRC holds.
TEST_F(PassthroughByHand, AFunctionItDoesNotKnowIsSentAsHandedAndItsReplyDelimitedByItsCrc) {
  // 0x41: a user-defined function (Application Protocol 5: 65..72).
  ASSERT_EQ(d.apply(WriteOp::of_forward({0x41, 0x12, 0x34}), 1, now), WriteStatus::pending);
  ASSERT_TRUE(d.next_exchange(now));
  EXPECT_EQ(d.on_receive(rtu({0x41, 0xAB, 0xCD, 0xEF}), now).kind, RxKind::ack);
  const auto done = completions();
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].reply, (Bytes{0x41, 0xAB, 0xCD, 0xEF}));
}

TEST_F(PassthroughByHand, IdleItProbesPresenceAndAnExceptionProvesTheSlaveIsThere) {
  const auto probe = d.next_exchange(now);
  ASSERT_TRUE(probe);
  EXPECT_EQ(probe->frame, rtu({0x03, 0x00, 0x00, 0x00, 0x01}));
  EXPECT_FALSE(d.common().ready);
  EXPECT_EQ(d.on_receive(rtu({0x83, 0x02}), now).kind, RxKind::ack);
  EXPECT_TRUE(d.common().ready);
  EXPECT_TRUE(completions().empty());  // the probe answers no client
  // Not again before the poll interval.
  EXPECT_FALSE(d.next_exchange(now + 499ms));
  EXPECT_TRUE(d.next_exchange(now + 500ms));
}

TEST_F(PassthroughByHand, ItTakesNoCommandSetpointOrPointAndNoEmptyOrOverlongPdu) {
  const WriteOp run = WriteOp::of_command(Command::run_forward);
  EXPECT_EQ(d.check(std::span(&run, 1)), WriteCheck::invalid_value);
  const WriteOp speed = WriteOp::of_setpoint(1500);
  EXPECT_EQ(d.check(std::span(&speed, 1)), WriteCheck::invalid_value);
  EXPECT_EQ(d.apply(WriteOp::of_forward({}), 1, now), WriteStatus::invalid_value);
  EXPECT_EQ(d.apply(WriteOp::of_forward(Bytes(254, 0x10)), 2, now), WriteStatus::invalid_value);
}

TEST_F(PassthroughByHand, OneNotOnTheLineInTimeIsFailedAndNeverSent) {
  ASSERT_EQ(d.apply(WriteOp::of_forward({0x06, 0x00, 0x01, 0x00, 0x03}), 5, now),
            WriteStatus::pending);
  // Long after: the gateway could no longer answer the client with it.
  const auto ex = d.next_exchange(now + d.traits().write_timeout);
  ASSERT_TRUE(ex);
  EXPECT_EQ(ex->frame, rtu({0x03, 0x00, 0x00, 0x00, 0x01}));  // the probe, not the write
  const auto done = completions();
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].result, WriteResult::no_response);
}

TEST_F(PassthroughByHand, CommLostFailsWhatWaitsAndForgetsThePresence) {
  ASSERT_TRUE(d.next_exchange(now));
  ASSERT_EQ(d.on_receive(rtu({0x03, 0x02, 0x00, 0x00}), now).kind, RxKind::ack);
  ASSERT_EQ(d.apply(WriteOp::of_forward(kReadRequest), 1, now), WriteStatus::pending);
  d.on_comm_lost(now);
  EXPECT_FALSE(d.common().ready);
  const auto done = completions();
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].result, WriteResult::no_response);
}

TEST(PassthroughAscii, TheFrameIsAsciiAndSoIsTheReply) {
  PassthroughSettings s;
  s.framing = Framing::ascii;
  PassthroughDriver d{kSlave, s, kCharTime, 500ms};
  const TimePoint now = TimePoint{} + 1s;
  ASSERT_EQ(d.apply(WriteOp::of_forward(kReadRequest), 1, now), WriteStatus::pending);
  const auto ex = d.next_exchange(now);
  ASSERT_TRUE(ex);
  EXPECT_EQ(ex->frame, encode(Framing::ascii, kSlave, kReadRequest));
  EXPECT_EQ(ex->frame.front(), ':');
  EXPECT_EQ(d.traits().inter_frame_gap, Millis(0));  // Serial Line 2.5.2: no silence needed
  EXPECT_EQ(d.on_receive(encode(Framing::ascii, kSlave, kReadReply), now).kind, RxKind::ack);
  std::vector<Completion> done;
  d.take_completions(done);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].reply, kReadReply);
}

// --- on the bus engine ---

// The outcome of one forwarded request, and the reply.
struct Forwarded {
  std::optional<Outcome> outcome;
  Bytes reply;
};

class PassthroughOnTheBus : public ::testing::Test {
 protected:
  test::BusRig rig{drivegate_adapter};
  // A profile device (the example VFD at 7) and a pass-through window at 9, one simulated slave
  // each, on one line.
  Device& vfd = rig.add_device("vfd", 7);
  Device& pass = rig.add_device("pass", 9, {{"passthrough", "true"}});

  void SetUp() override {
    rig.add_simulator(7);
    rig.add_simulator(9);
  }

  std::shared_ptr<Forwarded> forward(Bytes pdu, const Session& session = test::BusRig::kMaintain) {
    auto f = std::make_shared<Forwarded>();
    const Outcome at_once = pass.forward(
        session, pdu,
        [f](Outcome o, std::span<const std::uint8_t> reply) {
          f->outcome = o;
          f->reply.assign(reply.begin(), reply.end());
        },
        rig.now());
    if (at_once != Outcome::ok) f->outcome = at_once;
    return f;
  }
  bool settle(const std::shared_ptr<Forwarded>& f, Millis limit = 3s) {
    return rig.run_until([&] { return f->outcome.has_value(); }, limit);
  }
};

TEST_F(PassthroughOnTheBus, AReadAndAWriteAreTheSlavesOwnAnswersAndTheWriteReachesIt) {
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return vfd.online() && pass.state().ready; }, 3s));
  EXPECT_TRUE(pass.forwards());
  EXPECT_FALSE(vfd.forwards());
  // FC 06: the example profile's speed_reference (holding 1) := 1234; the slave echoes it.
  const Bytes write = {0x06, 0x00, 0x01, 0x04, 0xD2};
  const auto w = forward(write);
  ASSERT_TRUE(settle(w));
  EXPECT_EQ(w->outcome, Outcome::ok);
  EXPECT_EQ(w->reply, write);  // Application Protocol 6.6: the echo
  // The frame on the wire was the request as it is, at slave 9.
  bool seen = false;
  for (const auto& f : rig.sent()) seen = seen || f.bytes == rtu(write);
  EXPECT_TRUE(seen);
  // FC 03 reads it back through the window.
  const auto r = forward({0x03, 0x00, 0x01, 0x00, 0x01});
  ASSERT_TRUE(settle(r));
  EXPECT_EQ(r->reply, (Bytes{0x03, 0x02, 0x04, 0xD2}));
  // A register the slave lacks: its exception, as it came.
  const auto missing = forward({0x03, 0x13, 0x88, 0x00, 0x01});
  ASSERT_TRUE(settle(missing));
  EXPECT_EQ(missing->outcome, Outcome::ok);
  EXPECT_EQ(missing->reply, (Bytes{0x83, 0x02}));
}

TEST_F(PassthroughOnTheBus, AReadClientForwardsReadsOnlyAndOperateHasNoWritesThrough) {
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return pass.state().ready; }, 3s));
  const Session read{AccessLevel::read, drivegate::WordOrder::big};
  const Session operate{AccessLevel::operate, drivegate::WordOrder::big};
  const std::size_t sent_before = rig.sent().size();
  EXPECT_EQ(forward({0x06, 0x00, 0x01, 0x00, 0x05}, read)->outcome, Outcome::denied);
  EXPECT_EQ(forward({0x10, 0x00, 0x00, 0x00, 0x01, 0x02, 0x00, 0x0F}, operate)->outcome,
            Outcome::denied);
  EXPECT_EQ(
      forward({0x17, 0x00, 0x64, 0x00, 0x01, 0x00, 0x00, 0x00, 0x01, 0x02, 0x00, 0x0F}, operate)
          ->outcome,
      Outcome::denied);
  // Nothing of them went on the line: the probe may have, a write may not.
  for (std::size_t i = sent_before; i < rig.sent().size(); ++i) {
    EXPECT_NE(rig.sent()[i].bytes[1], 0x06);
    EXPECT_NE(rig.sent()[i].bytes[1], 0x10);
  }
  const auto r = forward({0x04, 0x00, 0xC8, 0x00, 0x01}, read);
  ASSERT_TRUE(settle(r));
  EXPECT_EQ(r->outcome, Outcome::ok);
  EXPECT_EQ(r->reply.at(0), 0x04);
  // MEI 0x0E (read device identification) reads; another MEI type may write.
  const auto id = forward({0x2B, 0x0E, 0x01, 0x00}, read);
  EXPECT_NE(id->outcome, Outcome::denied);
  EXPECT_EQ(forward({0x2B, 0x0D, 0x00}, read)->outcome, Outcome::denied);
}

TEST_F(PassthroughOnTheBus, AFloodOfForwardsNeverStarvesTheOtherDevicesPolls) {
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return vfd.online() && pass.state().ready; }, 3s));
  // A client that keeps the window's queue full for 10 s: four in flight, refused busy past it.
  std::size_t answered = 0;
  std::size_t busy = 0;
  std::vector<std::shared_ptr<Forwarded>> flood;
  const TimePoint end = rig.now() + 10s;
  while (rig.now() < end) {
    std::erase_if(flood, [&](const auto& f) {
      if (!f->outcome) return false;
      if (f->outcome == Outcome::ok) ++answered;
      if (f->outcome == Outcome::busy) ++busy;
      return true;
    });
    while (flood.size() < kMaxQueuedWrites + 2)
      flood.push_back(forward({0x03, 0x00, 0x64, 0x00, 0x01}));
    rig.run_for(5ms);
    // The other device never goes comm_lost nor stale beyond a few of its polls.
    ASSERT_FALSE(vfd.comm_lost());
    const auto age = rig.value(vfd, "data_age_ms");
    ASSERT_LT(age, 2000u) << "the profile device was starved";
  }
  EXPECT_GT(answered, 20u);
  EXPECT_GT(busy, 0u);  // the queue is bounded, never a backlog
}

// Access levels share the queue fairly: eight read clients keeping 4 reads each in flight (32
// at once, far past the queue) never get a maintain client's write refused busy. Each write is
// taken, reaches the slave and is confirmed with its echo, while the reads go on being answered.
TEST_F(PassthroughOnTheBus, ReadClientsFillingTheQueueNeverLockAWriteOut) {
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return pass.state().ready; }, 3s));
  const Session read{AccessLevel::read, drivegate::WordOrder::big};
  constexpr std::size_t kReaders = 8;
  constexpr std::size_t kPipelined = 4;
  std::vector<std::shared_ptr<Forwarded>> reads;
  std::size_t reads_answered = 0;
  const auto keep_reading = [&] {
    std::erase_if(reads, [&](const auto& f) {
      if (f->outcome == Outcome::ok) ++reads_answered;
      return f->outcome.has_value();
    });
    while (reads.size() < kReaders * kPipelined) {
      reads.push_back(forward({0x03, 0x00, 0x64, 0x00, 0x01}, read));
    }
  };
  for (std::uint16_t value = 100; value < 110; ++value) {
    keep_reading();
    // FC 06: the example profile's speed_reference (holding 1).
    const Bytes write = {0x06, 0x00, 0x01, static_cast<std::uint8_t>(value >> 8),
                         static_cast<std::uint8_t>(value)};
    const auto w = forward(write);
    ASSERT_NE(w->outcome, Outcome::busy) << "a write refused busy for the reads queued ahead";
    while (!w->outcome) {
      rig.run_for(5ms);
      keep_reading();
    }
    EXPECT_EQ(w->outcome, Outcome::ok);
    EXPECT_EQ(w->reply, write);  // the slave's echo: it took it
  }
  EXPECT_GT(reads_answered, 20u);
  // The slave holds the last value written, read once the readers' last reads are answered.
  ASSERT_TRUE(rig.run_until(
      [&] {
        return std::all_of(reads.begin(), reads.end(),
                           [](const auto& f) { return f->outcome.has_value(); });
      },
      5s));
  const auto r = forward({0x03, 0x00, 0x01, 0x00, 0x01});
  ASSERT_TRUE(settle(r));
  EXPECT_EQ(r->reply, (Bytes{0x03, 0x02, 0x00, 109}));
}

TEST(PassthroughDead, ADeadSlaveIs0x0BAndCommLostWithoutStallingTheProfileDevice) {
  test::BusRig rig{drivegate_adapter};
  Device& vfd = rig.add_device("vfd", 7);
  Device& pass = rig.add_device("pass", 9, {{"passthrough", "true"}});
  rig.add_simulator(7);  // nobody at 9
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return vfd.online(); }, 3s));
  std::optional<Outcome> outcome;
  ASSERT_EQ(pass.forward(
                test::BusRig::kMaintain, Bytes{0x03, 0x00, 0x00, 0x00, 0x01},
                [&](Outcome o, std::span<const std::uint8_t>) { outcome = o; }, rig.now()),
            Outcome::ok);
  ASSERT_TRUE(rig.run_until([&] { return outcome.has_value(); }, 3s));
  EXPECT_EQ(outcome, Outcome::no_response);
  ASSERT_TRUE(rig.run_until([&] { return pass.comm_lost(); }, 10s));
  // Now refused at once, and the profile device polled on throughout.
  EXPECT_EQ(
      pass.forward(test::BusRig::kMaintain, Bytes{0x03, 0x00, 0x00, 0x00, 0x01}, {}, rig.now()),
      Outcome::no_response);
  EXPECT_FALSE(vfd.comm_lost());
  EXPECT_LT(rig.value(vfd, "data_age_ms"), 2000u);
}

TEST(PassthroughOptions, AProfileBesidePassthroughIsAnErrorNamingBoth) {
  DeviceEnv env;
  env.address = 9;
  env.options = test::options_of(drivegate_adapter,
                                 {{"passthrough", "true"}, {"profile", "ed3100-standard"}});
  std::string error;
  EXPECT_EQ(drivegate_adapter.create_driver(env, error), nullptr);
  EXPECT_NE(error.find("pass-through device reads no profile"), std::string::npos) << error;
  env.options = test::options_of(drivegate_adapter, {{"passthrough", "true"}});
  auto d = drivegate_adapter.create_driver(env, error);
  ASSERT_NE(d, nullptr) << error;
  EXPECT_TRUE(d->forwards());
}

// The profile device's slave lacks input 203 (half of motor_current): its first block is searched
// while requests are forwarded to the slave at 9 on the same line. Every frame the master sends
// keeps 3.5 characters of silence after the line's last byte, and where it follows a reply at
// once (the search's reads, the forwarded requests, the polls) exactly the driver's gap: 2006 us
// at 19200 8E1, not 3 ms.
TEST_F(PassthroughOnTheBus, WhileAPlanHealsForwardedRequestsKeepTheMicrosecondGap) {
  const auto c = character_time(19200, Parity::even, 8, 1);
  const auto silence = c * 7 / 2;  // Serial Line 2.5.1.1
  const auto gap = inter_frame_gap(Framing::rtu, c);
  ASSERT_EQ(gap, 2006us);
  rig.line().turnaround = silence;  // the fastest slave the specification allows
  ASSERT_EQ(rig.simulator(0).control("missing input 203", rig.now()).rfind("ok", 0), 0u);
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return pass.state().ready; }, 3s));
  std::vector<std::shared_ptr<Forwarded>> forwarded;
  for (int i = 0; i < 6; ++i) {  // one after the other, as one client's requests go
    forwarded.push_back(forward({0x03, 0x00, 0x01, 0x00, 0x01}));
    ASSERT_TRUE(settle(forwarded.back()));
    EXPECT_EQ(forwarded.back()->outcome, Outcome::ok) << i;
  }
  ASSERT_TRUE(rig.run_until([&] { return vfd.online(); }, 3s));
  rig.run_for(1s);
  // The search: motor_current alone, refused twice; the forwarded requests among its reads.
  const Bytes probe = rtu({0x04, 0x00, 0xCA, 0x00, 0x02}, 7);
  std::size_t first_probe = 0;
  std::size_t last_probe = 0;
  std::size_t forwards_between = 0;
  const auto& sent = rig.sent();
  for (std::size_t i = 0; i < sent.size(); ++i) {
    if (sent[i].bytes != probe) continue;
    if (first_probe == 0) first_probe = i;
    last_probe = i;
  }
  ASSERT_GT(last_probe, first_probe);
  for (std::size_t i = first_probe; i < last_probe; ++i) forwards_between += sent[i].bytes[0] == 9;
  EXPECT_GE(forwards_between, 1u);
  // The silence before every master frame, from the last byte on the line before it.
  std::vector<std::pair<TimePoint, bool>> ends;  // when a frame's last byte left; from a slave
  for (const auto& f : sent) ends.emplace_back(f.at + c * static_cast<long>(f.bytes.size()), false);
  for (const auto& f : rig.answers()) {
    ends.emplace_back(f.at + c * static_cast<long>(f.bytes.size()), true);
  }
  std::sort(ends.begin(), ends.end());
  std::size_t at_once = 0;
  for (std::size_t i = 1; i < sent.size(); ++i) {
    const auto before = std::lower_bound(ends.begin(), ends.end(), std::pair{sent[i].at, false});
    ASSERT_NE(before, ends.begin());
    const auto quiet = sent[i].at - std::prev(before)->first;
    EXPECT_GE(quiet, silence) << "frame " << i;
    if (std::prev(before)->second && quiet < 3ms) {
      EXPECT_EQ(quiet, gap) << "frame " << i;
      ++at_once;
    }
  }
  EXPECT_GE(at_once, 10u);
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_passthrough_test
