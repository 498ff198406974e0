// The modbus driver played by hand against the example profile (adapters/modbus/profiles/
// example-vfd.toml), slave address 7: the exact frames it sends, and what the replies make of its
// points and of the common block.
#include "driver.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "example_profile.h"
#include "profile_support.h"

namespace drivegate::modbus_device::modbus_driver_test {
namespace {

using namespace std::chrono_literals;
using support::read_pdu;
using support::words_pdu;

constexpr std::uint8_t kSlave = 7;

using shipped::example;

Bytes frame(std::vector<std::uint8_t> pdu, std::uint8_t address = kSlave) {
  return encode(Framing::rtu, address, pdu);
}

class ModbusDriverTest : public support::DriverAtHand {
 protected:
  ModbusDriverTest() : DriverAtHand(kSlave, example()) {}
  RxVerdict answer(const Bytes& wire) { return d.on_receive(wire, now); }

  // One poll cycle of the example's four blocks, with these registers.
  void cycle(std::uint16_t status, std::uint16_t speed_raw, std::uint16_t fault,
             std::uint16_t control = 0x0006, std::uint16_t reference = 0) {
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));
    // 200: speed_actual; 201: unused; 202..203: motor_current 12.5 A, low word first.
    EXPECT_EQ(answer(frame(words_pdu(0x04, {speed_raw, 0xDEAD, 0x0000, 0x4148}))).kind,
              RxKind::reply);
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 210, 1)));
    EXPECT_EQ(answer(frame(words_pdu(0x04, {fault}))).kind, RxKind::reply);
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 0, 2)));
    EXPECT_EQ(answer(frame(words_pdu(0x03, {control, reference}))).kind, RxKind::reply);
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 100, 1)));
    EXPECT_EQ(answer(frame(words_pdu(0x03, {status}))).kind, RxKind::reply);
  }

  // The example's blocks after the first (fault code, control word and reference, status word),
  // answered with a stopped drive's registers.
  void rest_of_cycle() {
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 210, 1)));
    answer(frame(words_pdu(0x04, {0})));
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 0, 2)));
    answer(frame(words_pdu(0x03, {6, 0})));
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 100, 1)));
    answer(frame(words_pdu(0x03, {0})));
  }

  std::vector<Completion> completions() {
    std::vector<Completion> out;
    d.take_completions(out);
    return out;
  }
};

TEST_F(ModbusDriverTest, ReadsTheExampleInFourRequestsAndFillsTheCommonBlock) {
  EXPECT_FALSE(d.common().ready);
  cycle(/*status*/ 0x0000, /*speed*/ 0, /*fault*/ 0);
  EXPECT_TRUE(d.common().ready);
  EXPECT_FALSE(d.common().running);
  EXPECT_EQ(d.common().command, Command::stop);
  EXPECT_TRUE(d.common().faults.empty());
  // Only motor_current is the device's own: every other point is bound to the common block.
  ASSERT_EQ(d.points().size(), 1u);
  EXPECT_EQ(d.points()[0].name, "motor_current");
  EXPECT_EQ(d.points()[0].type, PointType::f32);
  EXPECT_EQ(d.points()[0].unit, "A");
  EXPECT_DOUBLE_EQ(as_double(d.values()[0]), 12.5);
  // Nothing more until the poll interval has passed.
  EXPECT_FALSE(d.next_exchange(now).has_value());
  EXPECT_EQ(d.wake_at(), now + 500ms);
  now += 500ms;
  EXPECT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));
}

TEST_F(ModbusDriverTest, ADriveFoundRunningIsShownRunning) {
  // status bit 2: running; 15000 x 0.1 = 1500 rpm; the reference holds 1500.
  cycle(0x0004, 15000, 0, 0x000F, 1500);
  EXPECT_TRUE(d.common().running);
  EXPECT_EQ(d.common().speed_rpm, 1500);
  EXPECT_EQ(d.common().command, Command::run_forward);
  EXPECT_EQ(d.common().setpoint_rpm, 1500);
}

TEST_F(ModbusDriverTest, FaultsFollowTheFaultBitAndTheMap) {
  cycle(0x0008, 0, 2);  // bit 3: fault; 2 = over_current
  EXPECT_TRUE(d.common().faults.has(Fault::over_current));
  EXPECT_EQ(d.common().native_fault, 2u);
  now += 500ms;
  cycle(0x0008, 0, 7);  // not in the map: other
  EXPECT_TRUE(d.common().faults.has(Fault::other));
  now += 500ms;
  cycle(0x0000, 0, 2);  // the bit says no fault is active, whatever code is left
  EXPECT_TRUE(d.common().faults.empty());
}

// A command written as FC 06 to the control word (holding 0) and what the slave answers: the
// write's result and the command in force after it.
struct CommandReply {
  const char* name;
  Command command;
  std::uint16_t control;  // the value on the wire
  Bytes reply;
  WriteResult result;
  Command in_force;
};

class ModbusDriverCommandTest : public ModbusDriverTest,
                                public ::testing::WithParamInterface<CommandReply> {};

// A command is in force only once the slave echoed it: before, and after any other answer, the
// drive is still stopped.
TEST_P(ModbusDriverCommandTest, IsInForceOnlyOnceTheSlaveEchoedIt) {
  const CommandReply& c = GetParam();
  cycle(0, 0, 0);
  const WriteOp op = WriteOp::of_command(c.command);
  ASSERT_EQ(d.check(std::span(&op, 1)), WriteCheck::ok);
  ASSERT_EQ(d.apply(op, 1, now), WriteStatus::pending);
  EXPECT_EQ(d.common().command, Command::stop);
  ASSERT_EQ(sent(), support::fc06_frame(kSlave, 0, c.control));
  EXPECT_EQ(answer(c.reply).kind, RxKind::ack);  // a write's reply holds no state
  EXPECT_THAT(completions(),
              ::testing::ElementsAre(::testing::FieldsAre(1u, c.result, ::testing::IsEmpty())));
  EXPECT_EQ(d.common().command, c.in_force);
}

INSTANTIATE_TEST_SUITE_P(
    , ModbusDriverCommandTest,
    ::testing::Values(
        // The echo of the run (0x000F).
        CommandReply{"RunEchoed", Command::run_forward, 0x000F,
                     frame({0x06, 0x00, 0x00, 0x00, 0x0F}), WriteResult::ok, Command::run_forward},
        // The slave says it holds 0x0006 in the control word: it did not take the run.
        CommandReply{"AnEchoOfAnotherValue", Command::run_forward, 0x000F,
                     frame({0x06, 0x00, 0x00, 0x00, 0x06}), WriteResult::refused, Command::stop},
        // Exception 04 to the run reverse (0x080F): refused, and nothing changes.
        CommandReply{"AnException", Command::run_reverse, 0x080F, frame({0x86, 0x04}),
                     WriteResult::refused, Command::stop}),
    [](const ::testing::TestParamInfo<CommandReply>& i) { return std::string(i.param.name); });

TEST_F(ModbusDriverTest, SetpointsAreWrittenInTheReferencesUnitsWithinItsLimits) {
  cycle(0, 0, 0);
  const WriteOp too_fast = WriteOp::of_setpoint(3001);  // speed_reference max = 3000
  EXPECT_EQ(d.check(std::span(&too_fast, 1)), WriteCheck::invalid_value);
  const WriteOp backwards = WriteOp::of_setpoint(-1);  // min = 0
  EXPECT_EQ(d.check(std::span(&backwards, 1)), WriteCheck::invalid_value);
  const WriteOp ok = WriteOp::of_setpoint(1200);
  ASSERT_EQ(d.apply(ok, 2, now), WriteStatus::pending);
  const Bytes request = frame({0x06, 0x00, 0x01, 0x04, 0xB0});
  ASSERT_EQ(sent(), request);
  answer(request);
  EXPECT_EQ(d.common().setpoint_rpm, 1200);
}

TEST_F(ModbusDriverTest, AStopOvertakesARunStillWaitingForTheLine) {
  cycle(0, 0, 0);
  const WriteOp run = WriteOp::of_command(Command::run_forward);
  const WriteOp stop = WriteOp::of_command(Command::stop);
  ASSERT_EQ(d.apply(run, 1, now), WriteStatus::pending);
  ASSERT_EQ(d.apply(stop, 2, now), WriteStatus::pending);
  EXPECT_THAT(completions(), ::testing::ElementsAre(::testing::FieldsAre(
                                 1u, WriteResult::no_response, ::testing::IsEmpty())));
  EXPECT_EQ(sent(), frame({0x06, 0x00, 0x00, 0x00, 0x06}));  // the run never goes out
}

TEST_F(ModbusDriverTest, ARefusedBlockIsSearchedAndAMissingPointLeftOut) {
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));
  EXPECT_EQ(answer(frame({0x84, 0x02})).kind, RxKind::ack);  // illegal data address
  // The search, at once: the speed alone (read), so the rest holds the refusal: the unused 201
  // alone (read), so the current holds it: refused twice in a row alone.
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 1)));
  EXPECT_EQ(answer(frame(words_pdu(0x04, {15000}))).kind, RxKind::reply);
  EXPECT_EQ(d.common().speed_rpm, 0);  // read, and published once the search ends
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 201, 1)));
  EXPECT_EQ(answer(frame(words_pdu(0x04, {0}))).kind, RxKind::reply);
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 202, 2)));
  EXPECT_EQ(answer(frame({0x84, 0x02})).kind, RxKind::ack);
  std::vector<std::string> notices;
  d.take_notices(notices);
  EXPECT_TRUE(notices.empty());
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 202, 2)));
  EXPECT_EQ(answer(frame({0x84, 0x02})).kind, RxKind::ack);
  // Unknown now, and skipped: said once, with the plan that reads the rest.
  EXPECT_TRUE(std::holds_alternative<std::monostate>(d.values()[0]));
  EXPECT_EQ(d.common().speed_rpm, 1500);
  d.take_notices(notices);
  EXPECT_THAT(notices,
              ::testing::ElementsAre(
                  ::testing::StartsWith("point motor_current (input 202..203) is refused by the "
                                        "slave (exception 02)"),
                  ::testing::StartsWith("read plan: input 200, input 210, holding 0..1, holding "
                                        "100; skips input 202..203 (refused by the slave")));
  // The cycle is read anew by the new plan, and so is every cycle after it.
  for (int cycle = 0; cycle < 3; ++cycle) {
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 1)));
    answer(frame(words_pdu(0x04, {15000})));
    rest_of_cycle();
    EXPECT_EQ(sent(), Bytes{});
    now += 500ms;
  }
  d.take_notices(notices);
  EXPECT_EQ(notices.size(), 2u);  // nothing more said
}

// A read refused with anything but 02 (here 06, busy) is not a missing register: the same
// block is asked again at the next cycle, and after each further refusal one cycle, three,
// seven... later, at most the comm timeout (3 s) apart; answered, it is read every cycle again.
TEST_F(ModbusDriverTest, ARefusedReadIsAskedAgainAtTheNextCycleThenBackedOff) {
  cycle(0, 0, 0);
  const Bytes status = frame(read_pdu(0x03, 100, 1));
  const auto refuse_status_for = [&](Millis span) {
    std::vector<TimePoint> asked;
    const TimePoint end = now + span;
    for (; now < end; now += 500ms) {
      for (Bytes f = sent(); !f.empty(); f = sent()) {
        if (f == status) {
          asked.push_back(now);
          EXPECT_EQ(answer(frame({0x83, 0x06})).kind, RxKind::ack);
        } else {
          answer(frame(words_pdu(f[1], std::vector<std::uint16_t>(f[5], 0))));
        }
      }
    }
    return asked;
  };
  now += 500ms;
  const TimePoint start = now;
  const auto asked = refuse_status_for(12s);
  // Cycles 0, 1, then 1 skipped, 3, 5 (capped at 3 s)...
  ASSERT_GE(asked.size(), 6u);
  EXPECT_EQ(asked[0] - start, 0ms);
  EXPECT_EQ(asked[1] - asked[0], 500ms);
  EXPECT_EQ(asked[2] - asked[1], 1000ms);
  EXPECT_EQ(asked[3] - asked[2], 2000ms);
  EXPECT_EQ(asked[4] - asked[3], 3000ms);
  EXPECT_EQ(asked[5] - asked[4], 3000ms);
  // The state is as old as the status word's last good read, however fresh the other blocks.
  ASSERT_TRUE(d.state_read_at());
  EXPECT_EQ(*d.state_read_at(), start - 500ms);
  EXPECT_TRUE(d.traits().state_in_parts);
}

// The state's time is its oldest part's: speed (input 200), fault code (input 210) and status
// word (holding 100) read at different moments.
TEST_F(ModbusDriverTest, TheStateIsAsOldAsItsOldestPart) {
  EXPECT_FALSE(d.state_read_at());
  const TimePoint first = now;
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));
  answer(frame(words_pdu(0x04, {0, 0, 0, 0})));
  EXPECT_FALSE(d.state_read_at());  // the rest never read
  now += 20ms;
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 210, 1)));
  answer(frame(words_pdu(0x04, {0})));
  now += 20ms;
  ASSERT_EQ(sent(), frame(read_pdu(0x03, 0, 2)));
  answer(frame(words_pdu(0x03, {6, 0})));
  now += 20ms;
  ASSERT_EQ(sent(), frame(read_pdu(0x03, 100, 1)));
  answer(frame(words_pdu(0x03, {0})));
  EXPECT_EQ(d.state_read_at(), first);
  now = first + 500ms;
  const TimePoint second = now;
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));
  answer(frame(words_pdu(0x04, {0, 0, 0, 0})));
  // Until the cycle's last block, the state is the last cycle's, as old as it was.
  EXPECT_EQ(d.state_read_at(), first);
  now += 20ms;
  rest_of_cycle();
  EXPECT_EQ(d.state_read_at(), second);
  d.on_comm_lost(now);
  EXPECT_FALSE(d.state_read_at());  // whole again only once every part is read anew
}

// The fault bit (status word, holding 100) and the fault code (input 210) are read in different
// blocks of one cycle: published together at the cycle's end, the PLC reads the fault with its
// code, then no fault, and never one without the other (a fault of code 17, other, while the
// code that clears it waits for the status word of the same cycle).
TEST_F(ModbusDriverTest, AFaultAndItsCodeArePublishedTogether) {
  cycle(/*status*/ 0x0000, /*speed*/ 0, /*fault*/ 0);
  const auto only = [](Fault f) {
    FaultSet s;
    s.set(f);
    return s;
  };
  const auto every_block = [&](std::uint16_t status, std::uint16_t fault, const FaultSet& before,
                               const FaultSet& after) {
    now += 500ms;
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));
    answer(frame(words_pdu(0x04, {0, 0, 0, 0x4148})));
    EXPECT_EQ(d.common().faults, before);
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 210, 1)));
    answer(frame(words_pdu(0x04, {fault})));
    EXPECT_EQ(d.common().faults, before);
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 0, 2)));
    answer(frame(words_pdu(0x03, {6, 0})));
    EXPECT_EQ(d.common().faults, before);
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 100, 1)));
    answer(frame(words_pdu(0x03, {status})));
    EXPECT_EQ(d.common().faults, after);
  };
  // Trips with code 5 (drive_over_temperature), then is reset: code 0 and the bit clear.
  every_block(0x0008, 5, FaultSet{}, only(Fault::drive_over_temperature));
  every_block(0x0000, 0, only(Fault::drive_over_temperature), FaultSet{});
}

TEST_F(ModbusDriverTest, OnlyTheAwaitedReplyIsTaken) {
  ASSERT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));
  // Another slave's reply, and one of the wrong length, are not the reply.
  EXPECT_EQ(answer(frame(words_pdu(0x04, {1, 2, 3, 4}), 8)).kind, RxKind::foreign);
  EXPECT_EQ(answer(frame(words_pdu(0x04, {1, 2}))).kind, RxKind::foreign);
  EXPECT_EQ(answer(frame(words_pdu(0x03, {1, 2, 3, 4}))).kind, RxKind::foreign);
  // A damaged reply from this slave costs an attempt; bytes from elsewhere are skipped.
  Bytes damaged = frame(words_pdu(0x04, {1, 2, 3, 4}));
  damaged[4] ^= 0xFF;
  EXPECT_EQ(answer(damaged).kind, RxKind::bad_checksum);
  damaged[0] = 9;
  EXPECT_EQ(answer(damaged).kind, RxKind::noise);
  EXPECT_EQ(answer(frame(words_pdu(0x04, {1, 2, 3, 4}))).kind, RxKind::reply);
}

TEST_F(ModbusDriverTest, CommLostFailsEveryWriteStillWaiting) {
  cycle(0, 0, 0);
  const WriteOp run = WriteOp::of_command(Command::run_forward);
  ASSERT_EQ(d.apply(run, 9, now), WriteStatus::pending);
  d.on_comm_lost(now);
  EXPECT_THAT(completions(), ::testing::ElementsAre(::testing::FieldsAre(
                                 9u, WriteResult::no_response, ::testing::IsEmpty())));
  EXPECT_FALSE(d.common().ready);
  EXPECT_EQ(sent(), frame(read_pdu(0x04, 200, 4)));  // everything is asked again
}

TEST_F(ModbusDriverTest, TimingFollowsTheLine) {
  // At 19200 baud 3.5 characters of 0.573 ms (2.005 ms; the fixed 1.75 ms is for faster lines),
  // kept to the microsecond (Serial Line 2.5.1.1).
  EXPECT_EQ(d.traits().inter_frame_gap, 2006us);  // 3.5 x 572.917 us, to the next microsecond
  EXPECT_GE(d.traits().write_timeout, 3000ms);
  const auto ex = d.next_exchange(now);
  ASSERT_TRUE(ex);
  EXPECT_EQ(ex->attempts, 3);
  // 100 ms of the profile, and the 13-byte reply on the wire (7.4 ms): 108 ms.
  EXPECT_EQ(ex->timeout, 108ms);
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_driver_test
