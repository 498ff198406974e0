// PLC-loss failsafe end to end (issue 8, "Not done until"): the real daemon and a simulated
// nidec-washer; a Modbus client runs the drive, then goes away. The gateway stops the drive
// within failsafe_timeout + one poll cycle, status bit 5 (failsafe) latches, a setpoint alone
// does not restart it, a fresh run command does. Also: on_shutdown = hold.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <iostream>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr auto kTimeout = 1000ms;  // failsafe_timeout_ms below
constexpr auto kPoll = 500ms;      // poll_ms below
constexpr std::uint16_t kFailsafe = 1 << 5;

std::string config(const std::filesystem::path& port, const std::string& extra) {
  return "[[bus]]\nname = \"washer-line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"washer\"\nbus = \"washer-line\"\nadapter = \"nidec-washer\"\n"
         "unit_id = 1\npoll_ms = 500\nfailsafe_timeout_ms = 1000\n" +
         extra + "[device.options]\nplatform = 8\n";
}

class SafetyE2E : public ::testing::Test {
 protected:
  explicit SafetyE2E(const std::string& extra = "failsafe_action = \"stop\"\n")
      : sim_("nidec-washer", dir_ / "washer"), daemon_(dir_, config(dir_ / "washer", extra)) {}
  void SetUp() override {
    ASSERT_TRUE(observer_.connect());
    ASSERT_TRUE(eventually([&] { return (status() & reg::online) != 0; }, 10s))
        << "never online; sim says " << sim_.control("state");
  }
  // Reads do not feed the failsafe: the observer only reads.
  std::uint16_t status() { return observer_.input(reg::status, 1).regs.at(0); }
  bool sim_stopped() {
    const auto s = sim_.control("state");
    return s.find("motion=stop") != std::string::npos;
  }
  TempDir dir_;
  Sim sim_;
  Daemon daemon_;
  Plc observer_{daemon_.port()};
};

TEST_F(SafetyE2E, PlcLossStopsTheDriveWithinTheTimeoutPlusOnePollAndLatches) {
  auto last_write = std::chrono::steady_clock::now();
  {
    Plc plc(daemon_.port());
    ASSERT_TRUE(plc.connect());
    ASSERT_EQ(plc.write(reg::command, {1 /*run_forward*/, 800}), 0);
    ASSERT_THAT(sim_.control("state"), HasSubstr("target_rpm=800"));
    ASSERT_FALSE(sim_stopped());
    last_write = std::chrono::steady_clock::now();
  }  // the PLC closes its connection and is gone
  // Not before the timeout...
  std::this_thread::sleep_for(kTimeout - 300ms);
  EXPECT_FALSE(sim_stopped()) << "failsafe fired early";
  EXPECT_EQ(status() & kFailsafe, 0);
  // ...but within the timeout plus one poll cycle.
  ASSERT_TRUE(eventually([&] { return sim_stopped(); }, 5s)) << sim_.control("state");
  const auto took = std::chrono::steady_clock::now() - last_write;
  std::cerr << "drive stopped "
            << std::chrono::duration_cast<std::chrono::milliseconds>(took).count()
            << " ms after the last write\n";
  EXPECT_LT(took, kTimeout + kPoll)
      << std::chrono::duration_cast<std::chrono::milliseconds>(took).count() << " ms";
  RecordProperty(
      "stop_after_ms",
      static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(took).count()));
  EXPECT_EQ(status() & kFailsafe, kFailsafe);
  // Stop in force once the drive acknowledged it.
  EXPECT_TRUE(eventually([&] { return observer_.holding(reg::command, 1).regs.at(0) == 0; }, 5s));
  ASSERT_TRUE(eventually([&] { return (status() & reg::running) == 0; }, 5s));

  // A returning PLC: a setpoint alone is stored but does not restart the drive.
  Plc plc(daemon_.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_EQ(plc.write(reg::setpoint, {600}), 0);
  ASSERT_EQ(plc.write(reg::heartbeat, {1}), 0);
  std::this_thread::sleep_for(kPoll * 2);
  EXPECT_TRUE(sim_stopped()) << sim_.control("state");
  EXPECT_EQ(status() & kFailsafe, kFailsafe);
  EXPECT_EQ(observer_.holding(reg::setpoint, 1).regs.at(0), 600);

  // A fresh run command restarts it, at the stored setpoint, and clears the latch.
  ASSERT_EQ(plc.write(reg::command, {1 /*run_forward*/}), 0);
  EXPECT_THAT(sim_.control("state"),
              AllOf(HasSubstr("target_rpm=600"), Not(HasSubstr("motion=stop"))));
  EXPECT_EQ(status() & kFailsafe, 0);
}

TEST_F(SafetyE2E, AHeartbeatKeepsARunningDriveRunning) {
  Plc plc(daemon_.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_EQ(plc.write(reg::command, {1, 800}), 0);
  for (std::uint16_t beat = 0; beat < 12; ++beat) {
    ASSERT_EQ(plc.write(reg::heartbeat, {beat}), 0);
    std::this_thread::sleep_for(kTimeout / 4);
  }
  EXPECT_FALSE(sim_stopped()) << sim_.control("state");
  EXPECT_EQ(status() & kFailsafe, 0);
  EXPECT_EQ(observer_.holding(reg::heartbeat, 1).regs.at(0), 11);
}

TEST_F(SafetyE2E, ADaemonNobodyWroteToDoesNotTrip) {
  std::this_thread::sleep_for(kTimeout + kPoll);
  EXPECT_EQ(status() & kFailsafe, 0);
}

class HoldE2E : public SafetyE2E {
 protected:
  HoldE2E() : SafetyE2E("failsafe_action = \"hold\"\non_shutdown = \"hold\"\n") {}
};

TEST_F(HoldE2E, HoldLatchesTheBitAndLeavesTheDriveRunningAlsoAtShutdown) {
  {
    Plc plc(daemon_.port());
    ASSERT_TRUE(plc.connect());
    ASSERT_EQ(plc.write(reg::command, {1, 800}), 0);
  }
  ASSERT_TRUE(eventually([&] { return (status() & kFailsafe) != 0; }, 5s));
  EXPECT_FALSE(sim_stopped()) << sim_.control("state");
  EXPECT_EQ(daemon_.stop(), 0);
  EXPECT_THAT(sim_.control("state"),
              AllOf(HasSubstr("target_rpm=800"), Not(HasSubstr("motion=stop"))));
}

}  // namespace
}  // namespace drivegate::test
