// PLC-loss failsafe end to end: the real daemon and a simulated drive of the tests' own
// (test-drive, tests/support/test_adapter); a Modbus client runs the drive, then goes away. The
// gateway stops the drive within failsafe_timeout + one poll cycle, status bit 5 (failsafe)
// latches, a setpoint alone does not restart it, a fresh run command does. Also: on_shutdown =
// hold, and a reload that changes the running drive's device while the PLC is gone.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <iostream>

#include "e2e.h"
#include "http_get.h"

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
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
         "unit_id = 1\npoll_ms = 500\nfailsafe_timeout_ms = 1000\n" +
         extra;
}

class SafetyE2E : public ::testing::Test {
 protected:
  explicit SafetyE2E(const std::string& extra = "failsafe_action = \"stop\"\n")
      : sim_("test-drive", dir_ / "drive"), daemon_(dir_, config(dir_ / "drive", extra)) {}
  void SetUp() override {
    ASSERT_TRUE(observer_.connect());
    ASSERT_TRUE(eventually([&] { return (status() & reg::online) != 0; }, 10s))
        << "never online; sim says " << sim_.control("state");
  }
  // Reads do not feed the failsafe: the observer only reads.
  std::uint16_t status() { return observer_.input(reg::status, 1).regs.at(0); }
  // The simulated drive took a stop (or never ran): it does not turn, and aims at 0 rpm.
  bool sim_stopped() {
    const auto s = sim_.control("state");
    return s.find(" running=0 ") != std::string::npos && s.find(" target=0 ") != std::string::npos;
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
    ASSERT_THAT(sim_.control("state"), HasSubstr(" target=800 "));
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
  EXPECT_THAT(sim_.control("state"), AllOf(HasSubstr(" target=600 "), HasSubstr(" running=1 ")));
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
  EXPECT_THAT(sim_.control("state"), AllOf(HasSubstr(" target=800 "), HasSubstr(" running=1 ")));
}

// --- a reload that changes the device while its failsafe is armed ----------------------------

// The drive's device, with option one_way as asked: a reload that changes it replaces the device
// (its driver) while the drive runs on.
std::string changing_device(const std::filesystem::path& port, int http_port, bool one_way) {
  return "[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) +
         "\"\nrequests_per_s = 0\n\n[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"vfd\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
         "unit_id = 1\naddress = 1\npoll_ms = 500\nfailsafe_timeout_ms = 2000\n"
         "failsafe_action = \"stop\"\n[device.options]\none_way = " +
         (one_way ? "true" : "false") + "\n";
}

// The PLC runs the drive with a 2 s failsafe and goes away; half a second later a SIGHUP changes
// the device (a new driver, which finds the drive running). The new device inherits the
// watchdog: the drive is stopped within the deadline the PLC's last write set plus one poll
// cycle, the PLC reads the failsafe bit and the stop, and the history says the new device found
// the drive running (run_forward), as the log does, then that the failsafe tripped.
TEST(SafetyReloadE2E, ADeviceChangedWithThePlcGoneKeepsTheFailsafesDeadline) {
  TempDir dir;
  Sim sim("test-drive", dir / "line");
  const int http = free_port();
  Daemon daemon(dir, changing_device(dir / "line", http, false), {}, dir / "drivegated.log");
  Plc observer(daemon.port(), 1);
  ASSERT_TRUE(observer.connect());
  ASSERT_TRUE(eventually(
      [&] {
        const auto r = observer.input(reg::status, 1);
        return r.ok() && (r.regs[0] & reg::online) != 0;
      },
      10s));
  auto last_write = std::chrono::steady_clock::now();
  {
    Plc plc(daemon.port(), 1);
    ASSERT_TRUE(plc.connect());
    ASSERT_EQ(plc.write(reg::command, {1 /*run_forward*/, 1500}), 0);
    last_write = std::chrono::steady_clock::now();
  }  // the PLC is gone
  ASSERT_THAT(sim.control("state"), HasSubstr(" running=1 "));
  std::this_thread::sleep_for(500ms);
  std::ofstream(daemon.config()) << changing_device(dir / "line", http, true);
  daemon.process().signal(SIGHUP);
  // The drive took the stop from the moment it answered it; its speed then ramps down.
  ASSERT_TRUE(eventually(
      [&] {
        const auto s = sim.control("state");
        return s.find(" running=0 ") != std::string::npos &&
               s.find(" target=0 ") != std::string::npos;
      },
      8s))
      << "the failsafe never stopped the drive after the reload\n"
      << slurp(dir / "drivegated.log");
  const auto stopped = std::chrono::steady_clock::now() - last_write;
  std::cerr << "drive stopped "
            << std::chrono::duration_cast<std::chrono::milliseconds>(stopped).count()
            << " ms after the last write\n";
  EXPECT_LT(stopped, 2000ms + 500ms) << slurp(dir / "drivegated.log");  // deadline + a poll
  EXPECT_TRUE(
      eventually([&] { return sim.control("state").find(" speed=0 ") != std::string::npos; }, 5s));
  const std::string log = slurp(dir / "drivegated.log");
  EXPECT_THAT(log, HasSubstr("reload: device vfd changed (option one_way false -> true"));
  EXPECT_THAT(log, HasSubstr("device vfd: found running (run_forward"));
  // The registers: the failsafe bit latched, the stop in force, the drive stopped.
  EXPECT_TRUE(eventually(
      [&] {
        const auto s = observer.input(reg::status, 1);
        return s.ok() && (s.regs[0] & kFailsafe) != 0 && (s.regs[0] & reg::running) == 0;
      },
      5s));
  EXPECT_EQ(observer.holding(reg::command, 1).regs.at(0), 0);
  // The history: the new device found the drive running, then the failsafe tripped.
  const std::string started = http_get(http, "/api/v1/events?device=vfd&kind=drive_started").body;
  EXPECT_THAT(started, HasSubstr("found running (run_forward")) << started;
  EXPECT_THAT(started, Not(HasSubstr("running (stop"))) << started;
  EXPECT_THAT(http_get(http, "/api/v1/events?device=vfd&kind=failsafe_tripped").body,
              HasSubstr("failsafe stop"));
}

}  // namespace
}  // namespace drivegate::test
