// The PLC-loss failsafe of a device: armed by the first valid write to command,
// setpoint or heartbeat, tripped by the first tick after the timeout, latched in
// status bit 5 until a run command is written, and kept: a drive that runs again is stopped again.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include "fake_adapter.h"
#include "gateway/device.h"

namespace drivegate::failsafe_test {
namespace {

using namespace std::chrono_literals;

constexpr std::uint16_t kFailsafeBit = 1u << 5;  // StatusBit::failsafe
constexpr std::uint16_t kCommand = 0, kSetpoint = 1, kHeartbeat = 2, kLimit = 16;

class FailsafeTest : public ::testing::Test {
 protected:
  void make(FailsafeAction action, Millis timeout = 1000ms, std::int32_t preset = 0) {
    DeviceConfig cfg;
    cfg.name = "dev";
    cfg.unit_id = 1;
    cfg.failsafe.timeout = timeout;
    cfg.failsafe.action = action;
    cfg.failsafe.preset_rpm = preset;
    auto driver = std::make_unique<test::FakeDriver>(DeviceEnv{});
    driver->traits_.comm_timeout = 2000ms;
    driver->traits_.write_timeout = 60s;
    driver->common_.ready = true;
    fake_ = driver.get();
    device_ = std::make_unique<Device>(
        cfg, test::kFakeAdapter, std::move(driver),
        std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>()),
        t0_);
    device_->link().health.frame_good(t0_);
  }
  TimePoint at(Millis ms) const { return t0_ + ms; }
  // What the bus engine does at each tick (bus/bus_engine.cpp): comm_lost when due, then the
  // device's own tick.
  void engine_tick(Millis ms) {
    Link& link = device_->link();
    if (link.health.lost_by(at(ms), link.policy.comm_timeout)) device_->on_comm_lost(at(ms));
    device_->on_tick(at(ms));
  }
  // One tick with the drive answering.
  void tick(Millis ms) {
    device_->link().health.frame_good(at(ms));
    engine_tick(ms);
  }
  Outcome plc(std::uint16_t address, std::vector<std::uint16_t> v, Millis ms,
              AccessLevel access = AccessLevel::operate) {
    const Session session{access, WordOrder::big};
    const Outcome result = device_->write(
        session, Table::holding, address, v, [this](Outcome e) { answers_.push_back(e); }, at(ms));
    device_->next_exchange(at(ms), Turn::write);  // the engine's write turn
    return result;
  }
  // The driver confirms the write it was last given; the engine's next write turn follows.
  void confirm(Millis ms, WriteResult r = WriteResult::ok) {
    fake_->completions.push_back({fake_->last_ticket, r});
    device_->next_exchange(at(ms), Turn::poll);
    device_->next_exchange(at(ms), Turn::write);
  }
  static inline const Session kReader{AccessLevel::read, WordOrder::big};
  std::uint16_t status(Millis ms) {
    std::uint16_t s = 0;
    EXPECT_EQ(device_->read(kReader, Table::input, 0, std::span<std::uint16_t>(&s, 1), at(ms)),
              Outcome::ok);
    return s;
  }
  std::uint16_t holding_value(std::uint16_t address) {
    std::uint16_t v = 0;
    EXPECT_EQ(device_->read(kReader, Table::holding, address, std::span<std::uint16_t>(&v, 1), t0_),
              Outcome::ok);
    return v;
  }
  bool discrete_failsafe(Millis ms) {
    std::uint16_t b = 0;
    EXPECT_EQ(device_->read(kReader, Table::discrete, 5, std::span<std::uint16_t>(&b, 1), at(ms)),
              Outcome::ok);
    return b != 0;
  }

  TimePoint t0_ = TimePoint{} + std::chrono::hours(1);
  test::FakeDriver* fake_ = nullptr;
  std::unique_ptr<Device> device_;
  std::vector<Outcome> answers_;
};

TEST_F(FailsafeTest, AGatewayNobodyWroteToNeverTrips) {
  make(FailsafeAction::stop);
  for (int ms = 100; ms <= 10'000; ms += 100) tick(Millis(ms));
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_EQ(status(10'000ms) & kFailsafeBit, 0);
}

TEST_F(FailsafeTest, OffByDefault) {
  make(FailsafeAction::stop, 0ms);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  for (int ms = 100; ms <= 10'000; ms += 100) tick(Millis(ms));
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_FALSE(device_->failsafe_latched());
}

TEST_F(FailsafeTest, StopsAtTheFirstTickAfterTheTimeoutAndLatches) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kCommand, {1 /*run_forward*/, 800}, 0ms), Outcome::ok);
  fake_->common_.command = Command::run_forward;
  confirm(0ms);
  fake_->commands.clear();
  tick(900ms);
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_EQ(status(900ms) & kFailsafeBit, 0);
  tick(1000ms);
  ASSERT_EQ(fake_->commands, std::vector<Command>{Command::stop});
  EXPECT_EQ(status(1000ms) & kFailsafeBit, kFailsafeBit);
  EXPECT_TRUE(discrete_failsafe(1000ms));
  fake_->common_.command = Command::stop;
  confirm(1050ms);
  for (int ms = 1100; ms <= 5000; ms += 100) tick(Millis(ms));
  EXPECT_EQ(fake_->commands.size(), 1u);  // confirmed: not sent again
  EXPECT_EQ(status(5000ms) & kFailsafeBit, kFailsafeBit);
}

// A client whose writes do not prove the PLC is there (MQTT unless feed_failsafe): its writes go
// through but feed nothing, and while the failsafe is latched its run is refused (0x04) before
// the driver sees it: only the PLC's run clears the latch (docs/safety.md, "Command authority").
TEST_F(FailsafeTest, WritesFromANonFeedingSessionDoNotFeedIt) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kCommand, {1 /*run_forward*/, 800}, 0ms), Outcome::ok);
  fake_->common_.command = Command::run_forward;
  confirm(0ms);
  const Session mqtt{AccessLevel::operate, WordOrder::big, false};
  const std::uint16_t beat = 9;
  ASSERT_EQ(device_->write(
                mqtt, Table::holding, kHeartbeat, std::span(&beat, 1), [](Outcome) {}, at(900ms)),
            Outcome::ok);
  EXPECT_EQ(holding_value(kHeartbeat), 9);  // taken
  fake_->commands.clear();
  tick(1000ms);  // 1 s after the PLC's last write: trips all the same
  ASSERT_EQ(fake_->commands, std::vector<Command>{Command::stop});
  fake_->common_.command = Command::stop;
  confirm(1000ms);
  // A run from it is refused, the latch holds: it does not say the PLC is back.
  fake_->commands.clear();
  const std::uint16_t run = 1;
  EXPECT_EQ(device_->write(
                mqtt, Table::holding, kCommand, std::span(&run, 1), [](Outcome) {}, at(1100ms)),
            Outcome::refused);
  device_->next_exchange(at(1100ms), Turn::write);
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_TRUE(device_->failsafe_latched());
  EXPECT_EQ(device_->write_stats().refused_failsafe, 1u);
  // Nor with a setpoint in the same request: refused whole, the setpoint not stored.
  const std::vector<std::uint16_t> run_at = {1, 900};
  EXPECT_EQ(device_->write(
                mqtt, Table::holding, kCommand, run_at, [](Outcome) {}, at(1150ms)),
            Outcome::refused);
  EXPECT_EQ(fake_->setpoints.back(), 800);
  // The PLC's own run clears it.
  ASSERT_EQ(plc(kCommand, {1}, 1200ms), Outcome::ok);
  EXPECT_FALSE(device_->failsafe_latched());
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::run_forward});
}

TEST_F(FailsafeTest, EachOfCommandSetpointAndHeartbeatFeedsIt) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  ASSERT_EQ(plc(kSetpoint, {700}, 800ms), Outcome::ok);
  tick(1700ms);
  ASSERT_EQ(plc(kCommand, {0}, 1700ms), Outcome::ok);
  confirm(1700ms);
  fake_->commands.clear();
  tick(2600ms);
  ASSERT_EQ(plc(kHeartbeat, {2}, 2600ms), Outcome::ok);
  tick(3500ms);
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_FALSE(device_->failsafe_latched());
  tick(3600ms);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::stop});
}

TEST_F(FailsafeTest, AdapterPointsAndInvalidWritesDoNotFeedIt) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  ASSERT_EQ(plc(kLimit, {0, 50}, 500ms, AccessLevel::maintain),  // adapter point
            Outcome::ok);
  ASSERT_EQ(plc(kCommand, {9}, 600ms), Outcome::invalid_value);  // no such command
  tick(1000ms);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::stop});
  EXPECT_TRUE(device_->failsafe_latched());
}

// Only a write that succeeded proves the PLC is there: one the driver refuses at once (0x03), one
// the drive answers with an exception (0x04) and one to a drive that stopped answering (0x0B)
// feed nothing, so a client whose every write fails never keeps a running drive alive.
TEST_F(FailsafeTest, AWriteRefusedForAnyReasonFeedsNothing) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  fake_->check_answer = WriteCheck::invalid_value;
  EXPECT_EQ(plc(kSetpoint, {700}, 300ms), Outcome::invalid_value);
  fake_->check_answer = WriteCheck::ok;
  fake_->setpoint_answer = WriteStatus::pending;
  answers_.clear();
  ASSERT_EQ(plc(kSetpoint, {700}, 500ms), Outcome::ok);
  confirm(600ms, WriteResult::refused);
  EXPECT_EQ(answers_, std::vector<Outcome>{Outcome::refused});
  ASSERT_EQ(plc(kSetpoint, {710}, 700ms), Outcome::ok);
  confirm(800ms, WriteResult::no_response);
  tick(1000ms);  // 1 s after the heartbeat, the last write that succeeded
  EXPECT_TRUE(device_->failsafe_latched());
}

// Only a client allowed to operate is "the PLC": a read-only one (a SCADA viewer, a dashboard)
// writing the heartbeat is refused and keeps nothing alive.
TEST_F(FailsafeTest, AClientThatMayOnlyReadDoesNotFeedIt) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  EXPECT_EQ(plc(kHeartbeat, {2}, 600ms, AccessLevel::read), Outcome::denied);
  EXPECT_EQ(plc(kCommand, {1}, 700ms, AccessLevel::read), Outcome::denied);
  tick(1000ms);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::stop});
  EXPECT_TRUE(device_->failsafe_latched());
}

TEST_F(FailsafeTest, OnlyARunCommandWrittenAfterTheTripResetsIt) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  tick(1000ms);
  confirm(1000ms);
  ASSERT_TRUE(device_->failsafe_latched());
  fake_->commands.clear();

  // A setpoint is stored (passed to the driver, which keeps it for the next run), nothing starts.
  ASSERT_EQ(plc(kSetpoint, {650}, 1200ms), Outcome::ok);
  EXPECT_EQ(fake_->setpoints.back(), 650);
  EXPECT_TRUE(fake_->commands.empty());
  ASSERT_EQ(plc(kHeartbeat, {2}, 1300ms), Outcome::ok);
  ASSERT_EQ(plc(kCommand, {0 /*stop*/}, 1400ms), Outcome::ok);
  confirm(1400ms);
  ASSERT_EQ(plc(kCommand, {4 /*reset_fault*/}, 1500ms), Outcome::ok);
  confirm(1500ms);
  tick(1600ms);
  EXPECT_TRUE(device_->failsafe_latched());
  EXPECT_EQ(status(1600ms) & kFailsafeBit, kFailsafeBit);

  ASSERT_EQ(plc(kCommand, {2 /*run_reverse*/}, 1700ms), Outcome::ok);
  EXPECT_FALSE(device_->failsafe_latched());
  EXPECT_EQ(status(1700ms) & kFailsafeBit, 0);
  EXPECT_EQ(fake_->commands.back(), Command::run_reverse);
  // The timer runs again from that write.
  tick(2600ms);
  EXPECT_FALSE(device_->failsafe_latched());
  tick(2700ms);
  EXPECT_TRUE(device_->failsafe_latched());
}

TEST_F(FailsafeTest, ARunTheDriveRefusesAtOnceDoesNotResetIt) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  tick(1000ms);
  confirm(1000ms);
  fake_->answer = WriteStatus::refused;
  EXPECT_EQ(plc(kCommand, {1}, 1200ms), Outcome::refused);
  EXPECT_TRUE(device_->failsafe_latched());
}

TEST_F(FailsafeTest, ADriveThatRunsAgainWhileLatchedIsStoppedAgain) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  tick(1000ms);
  confirm(1000ms);
  // E.g. a driver that resumes the run in force after comm_lost.
  fake_->common_.command = Command::run_forward;
  device_->next_exchange(at(1500ms), Turn::poll);
  tick(1500ms);
  EXPECT_EQ(fake_->commands, (std::vector<Command>{Command::stop, Command::stop}));
}

TEST_F(FailsafeTest, AFailedStopIsRetriedAfterASecondNotOnEveryTick) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  tick(1000ms);
  confirm(1000ms, WriteResult::no_response);
  for (int ms = 1100; ms < 2000; ms += 100) tick(Millis(ms));
  EXPECT_EQ(fake_->commands.size(), 1u);
  tick(2000ms);
  EXPECT_EQ(fake_->commands.size(), 2u);
}

TEST_F(FailsafeTest, ATripDuringCommLostStopsTheDriveWhenItAnswersAgain) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  // No good frame from 0 on: comm_lost after 2 s, failsafe at 1 s with the drive already silent.
  for (int ms = 100; ms <= 3000; ms += 100) engine_tick(Millis(ms));
  EXPECT_TRUE(device_->failsafe_latched());
  EXPECT_TRUE(device_->comm_lost());
  fake_->commands.clear();  // the stop sent at 1 s failed at comm_lost (0x0B)
  tick(3100ms);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::stop});
}

TEST_F(FailsafeTest, QuickStopFallsBackToStopWhenTheDriveCannot) {
  make(FailsafeAction::quick_stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  fake_->answer = WriteStatus::invalid_value;
  tick(1000ms);
  fake_->answer = WriteStatus::pending;
  tick(1100ms);
  EXPECT_EQ(fake_->commands, (std::vector<Command>{Command::quick_stop, Command::stop}));
}

TEST_F(FailsafeTest, HoldOnlyLatchesTheBit) {
  make(FailsafeAction::hold);
  ASSERT_EQ(plc(kCommand, {1}, 0ms), Outcome::ok);
  fake_->common_.command = Command::run_forward;
  confirm(0ms);
  fake_->commands.clear();
  for (int ms = 100; ms <= 3000; ms += 100) tick(Millis(ms));
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_TRUE(fake_->setpoints.empty());
  EXPECT_EQ(status(3000ms) & kFailsafeBit, kFailsafeBit);
}

TEST_F(FailsafeTest, PresetSlowsARunningDriveAndLeavesAStoppedOne) {
  make(FailsafeAction::preset, 1000ms, 300);
  ASSERT_EQ(plc(kCommand, {1}, 0ms), Outcome::ok);
  fake_->common_.command = Command::run_forward;
  confirm(0ms);
  fake_->commands.clear();
  tick(1000ms);
  EXPECT_EQ(fake_->setpoints, std::vector<std::int32_t>{300});
  EXPECT_TRUE(fake_->commands.empty());
  tick(1100ms);
  EXPECT_EQ(fake_->setpoints.size(), 1u);  // taken once

  make(FailsafeAction::preset, 1000ms, 300);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  for (int ms = 100; ms <= 3000; ms += 100) tick(Millis(ms));
  EXPECT_TRUE(fake_->setpoints.empty());
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_TRUE(device_->failsafe_latched());
}

TEST_F(FailsafeTest, APresetTheDriveRefusesBecomesAStop) {
  make(FailsafeAction::preset, 1000ms, 300);
  ASSERT_EQ(plc(kCommand, {1}, 0ms), Outcome::ok);
  fake_->common_.command = Command::run_forward;
  confirm(0ms);
  fake_->commands.clear();
  fake_->setpoint_answer = WriteStatus::invalid_value;
  tick(1000ms);
  tick(1100ms);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::stop});
}

TEST_F(FailsafeTest, TheGatewaysOwnCommandsNeitherFeedNorReset) {
  make(FailsafeAction::stop);
  ASSERT_EQ(plc(kHeartbeat, {1}, 0ms), Outcome::ok);
  device_->command(
      Command::stop, [](Outcome) {}, at(900ms));
  tick(1000ms);
  EXPECT_TRUE(device_->failsafe_latched());
  device_->command(
      Command::run_forward, [](Outcome) {}, at(1100ms));
  EXPECT_TRUE(device_->failsafe_latched());
}

}  // namespace
}  // namespace drivegate::failsafe_test
