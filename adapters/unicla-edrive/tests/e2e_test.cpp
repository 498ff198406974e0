// unicla-edrive end to end: the daemon on simulated eDrives (RS-485, 19200 8N1), driven from
// Modbus TCP as a PLC would, and two eDrives sharing one line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <iostream>

#include "drive_e2e.h"
#include "e2e.h"
#include "e2e_adapters.h"

namespace drivegate::test::unicla_edrive_e2e_test {
namespace {

// How the core's scenarios on every drive (tests/e2e: capture, status page) run this one.
const RegisterE2eAdapter kE2eAdapter({.id = "unicla-edrive",
                                      .rpm = 3000,
                                      .protocol = "UNICLA-EDRIVE",
                                      .checksum_field = "unicla_edrive.crc.status"});

using namespace std::chrono_literals;
using ::testing::HasSubstr;

// The adapter's input points after the common block (`drivegate regmap`,
// adapters/unicla-edrive/points.cpp). Floats take two registers, high word first.
namespace ed {
inline constexpr int suction_pressure = 32, discharge_pressure = 34, suction_temperature = 36,
                     discharge_temperature = 38, suction_superheat = 40, discharge_superheat = 42,
                     compressor_rpm = 44, op_state = 48, motor_temperature = 53,
                     switch_temperature = 55, motor_safety_run = 59, model = 63;
}  // namespace ed

// Unified fault codes (include/drivegate/common.h).
inline constexpr std::uint16_t kCommLost = 1, kOverCurrent = 4;
// ED_OP_STATE values (the document's enum, labels.h): 3 Stopped, 7 Fault - Motor.
inline constexpr std::uint16_t kStopped = 3, kFaultMotor = 7;

float f32(const Plc::Read& r, std::size_t at) {
  return std::bit_cast<float>(r.u32(at));
}

std::string device(const std::string& name, int unit, int address, const std::string& extra = "") {
  return "\n[[device]]\nname = \"" + name + "\"\nbus = \"edrive-line\"\nadapter = " +
         "\"unicla-edrive\"\nunit_id = " + std::to_string(unit) +
         "\naddress = " + std::to_string(address) + "\n" + extra;
}

std::string bus(const std::filesystem::path& port) {
  return "[[bus]]\nname = \"edrive-line\"\nport = \"" + port.string() + "\"\n";
}

// String registers as text: two characters each, high byte first, cut at the first NUL.
std::string text(const Plc::Read& r) {
  std::string s;
  for (const auto w : r.regs) {
    for (const int c : {w >> 8, w & 0xFF}) {
      if (c == 0) return s;
      s.push_back(static_cast<char>(c));
    }
  }
  return s;
}

class EDriveE2E : public DriveE2E<> {
 protected:
  EDriveE2E()
      : DriveE2E("unicla-edrive", "edrive", {}, [](const std::filesystem::path& port) {
          return bus(port) + device("edrive", 1, 1);
        }) {}
};

TEST_F(EDriveE2E, ReadsPressuresAndTemperaturesAsFloats) {
  // The simulator at rest (adapters/unicla-edrive/simulator.cpp): equalised pressures.
  const auto r = plc_.input(ed::suction_pressure, 12);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.regs[0], 0x4090);  // 4.5f = 0x40900000: the high word comes first
  EXPECT_EQ(r.regs[1], 0x0000);
  EXPECT_FLOAT_EQ(f32(r, 0), 4.5F);    // suction pressure, bar-a
  EXPECT_FLOAT_EQ(f32(r, 2), 6.5F);    // discharge pressure, bar-a
  EXPECT_FLOAT_EQ(f32(r, 4), 12.0F);   // suction temperature, degC
  EXPECT_FLOAT_EQ(f32(r, 6), 25.0F);   // discharge temperature, degC
  EXPECT_FLOAT_EQ(f32(r, 8), 5.0F);    // suction superheat, K
  EXPECT_FLOAT_EQ(f32(r, 10), 10.0F);  // discharge superheat, K
  const auto t = plc_.input(ed::motor_temperature, 4);
  ASSERT_TRUE(t.ok());
  EXPECT_FLOAT_EQ(f32(t, 0), 30.0F);  // motor temperature, degC
  EXPECT_FLOAT_EQ(f32(t, 2), 35.0F);  // switch temperature, degC
  EXPECT_THAT(state(), HasSubstr("suction_pressure=4.5 discharge_pressure=6.5"));
  // Build information, read at start-up.
  EXPECT_EQ(text(plc_.input(ed::model, 8)), "EDRIVE-SIM-24V");
}

TEST_F(EDriveE2E, RunsAt3000AndBackTo0) {
  ASSERT_EQ(plc_.write(reg::command, {1 /*run_forward*/, 3000}), 0) << state();
  EXPECT_THAT(state(), HasSubstr("target=3000"));
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::speed, 1).regs[0] == 3000; }, 10s))
      << state();
  const auto r = plc_.input(reg::status, 9);
  EXPECT_TRUE(r.regs[0] & reg::running);
  EXPECT_LT(r.u32(reg::data_age), 1500u);  // polled every 500 ms
  EXPECT_EQ(plc_.input(ed::compressor_rpm, 1).regs[0], 3000);
  // Half the 6000 rpm maximum: the simulated plant's pressures follow the speed. The speed
  // register shows 3000 from 2999.5 rpm on while the drive's ramp ends, so the pressures are read
  // once a poll has carried the ramp's end.
  ASSERT_TRUE(eventually(
      [&] {
        const auto q = plc_.input(ed::suction_pressure, 4);
        return q.ok() && f32(q, 0) == 3.75F && f32(q, 2) == 11.5F;
      },
      5s))
      << state();
  const auto p = plc_.input(ed::suction_pressure, 4);
  EXPECT_FLOAT_EQ(f32(p, 0), 3.75F);
  EXPECT_FLOAT_EQ(f32(p, 2), 11.5F);
  EXPECT_EQ(plc_.holding(reg::command, 2).regs, (std::vector<std::uint16_t>{1, 3000}));

  ASSERT_EQ(plc_.write(reg::command, {0 /*stop*/}), 0);
  EXPECT_THAT(state(), HasSubstr("target=0"));
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::speed, 1).regs[0] == 0; }, 10s));
  EXPECT_EQ(plc_.input(ed::op_state, 1).regs[0], kStopped);
  EXPECT_FALSE(plc_.input(reg::status, 1).regs[0] & reg::running);
  EXPECT_EQ(plc_.holding(reg::command, 1).regs[0], 0);
}

TEST_F(EDriveE2E, Refuses7000With0x03) {
  EXPECT_EQ(plc_.write(reg::command, {1, 7000}), 0x03);
  EXPECT_EQ(plc_.write(reg::setpoint, {7000}), 0x03);
  EXPECT_EQ(plc_.write(reg::setpoint, {1000}), 0x03);    // under the running limit 1500
  EXPECT_EQ(plc_.write(reg::command, {2, 3000}), 0x03);  // run_reverse: one direction
  // Nothing was sent: the drive saw no write at all.
  EXPECT_THAT(state(), HasSubstr("writes=0"));
  EXPECT_THAT(state(), HasSubstr("target=0"));
  EXPECT_EQ(plc_.input(reg::speed, 1).regs[0], 0);
  // The limits themselves are accepted.
  EXPECT_EQ(plc_.write(reg::setpoint, {6000}), 0);
  EXPECT_EQ(plc_.write(reg::setpoint, {1500}), 0);
}

TEST_F(EDriveE2E, MotorFaultIsAUnifiedCodeThatResetFaultClears) {
  ASSERT_EQ(plc_.write(reg::command, {1, 3000}), 0);
  ASSERT_THAT(sim_.control("fault motor"), HasSubstr("op_state=7"));  // + ST over current
  ASSERT_TRUE(
      eventually([&] { return plc_.input(reg::fault_code, 1).regs[0] == kOverCurrent; }, 5s))
      << state();
  auto r = plc_.input(reg::status, 6);
  EXPECT_TRUE(r.regs[0] & reg::fault);
  EXPECT_EQ(r.u32(reg::fault_mask), 1u << kOverCurrent);
  EXPECT_EQ(r.u32(reg::native_fault), kFaultMotor);  // the op state
  EXPECT_EQ(plc_.input(ed::op_state, 1).regs[0], kFaultMotor);
  EXPECT_EQ(plc_.input(ed::motor_safety_run, 1).regs[0], 1u << 14);  // ST over current
  // A faulted drive will not run.
  EXPECT_EQ(plc_.write(reg::command, {1, 3000}), 0x04);

  ASSERT_EQ(plc_.write(reg::command, {4 /*reset_fault*/}), 0) << state();
  r = plc_.input(reg::status, 6);
  EXPECT_FALSE(r.regs[0] & reg::fault);
  EXPECT_EQ(r.regs[reg::fault_code], 0);
  EXPECT_EQ(r.u32(reg::fault_mask), 0u);
  EXPECT_EQ(r.u32(reg::native_fault), 0u);
  EXPECT_EQ(plc_.input(ed::motor_safety_run, 1).regs[0], 0);
  EXPECT_THAT(state(), HasSubstr("op_state=3"));
  // And it runs again.
  EXPECT_EQ(plc_.write(reg::command, {1, 3000}), 0);
}

TEST_F(EDriveE2E, AFaultThatStandsIsNotCleared) {
  sim_.control("sticky on");
  sim_.control("fault motor");
  ASSERT_TRUE(
      eventually([&] { return plc_.input(reg::fault_code, 1).regs[0] == kOverCurrent; }, 5s));
  EXPECT_EQ(plc_.write(reg::command, {4 /*reset_fault*/}), 0x04);
  EXPECT_EQ(plc_.input(reg::fault_code, 1).regs[0], kOverCurrent);
}

TEST_F(EDriveE2E, SilentDriveIsCommLostAndComesBack) {
  sim_.control("silent on");
  ASSERT_TRUE(
      eventually([&] { return (plc_.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 8s));
  const auto r = plc_.input(reg::status, 19);
  EXPECT_FALSE(r.regs[0] & reg::online);
  EXPECT_EQ(r.regs[reg::fault_code], kCommLost);
  EXPECT_GT(r.u32(reg::timeouts), 0u);
  EXPECT_EQ(plc_.write(reg::command, {1, 3000}), 0x0B);
  sim_.control("silent off");
  ASSERT_TRUE(comes_online(plc_));
  EXPECT_EQ(plc_.write(reg::command, {1, 3000}), 0);
}

// Two eDrives on one line: one `drivegate sim` answering ids 1 and 2 on one pty.
constexpr int kPollMs = 500;
constexpr int kBudgetMs = 1000;  // the silent one's budget (the default, stated here)

class TwoEDrivesE2E : public ::testing::Test {
 protected:
  TwoEDrivesE2E()
      : sim_("unicla-edrive", dir_ / "edrive", {"--address", "1", "--address", "2"}),
        daemon_(dir_, bus(dir_ / "edrive") +
                          device("left", 1, 1, "poll_ms = " + std::to_string(kPollMs) + "\n") +
                          device("right", 2, 2,
                                 "poll_ms = " + std::to_string(kPollMs) +
                                     "\nbudget_ms = " + std::to_string(kBudgetMs) + "\n")) {}
  void SetUp() override {
    ASSERT_TRUE(left_.connect());
    ASSERT_TRUE(right_.connect());
    for (Plc* plc : {&left_, &right_}) {
      ASSERT_TRUE(comes_online(*plc)) << sim_.control("state");
    }
  }
  // Samples the left drive's data age every 20 ms for `span`; returns the largest, and the
  // good frames it gained.
  std::pair<std::uint32_t, std::uint32_t> watch_left(std::chrono::milliseconds span) {
    const std::uint32_t frames_before = left_.input(reg::status, 19).u32(reg::frames_good);
    std::uint32_t worst = 0;
    const auto until = std::chrono::steady_clock::now() + span;
    while (std::chrono::steady_clock::now() < until) {
      const auto r = left_.input(reg::status, 19);
      EXPECT_TRUE(r.ok());
      EXPECT_TRUE(r.regs[0] & reg::online);
      worst = std::max(worst, r.u32(reg::data_age));
      std::this_thread::sleep_for(20ms);
    }
    return {worst, left_.input(reg::status, 19).u32(reg::frames_good) - frames_before};
  }
  TempDir dir_;
  Sim sim_;
  Daemon daemon_;
  Plc left_{daemon_.port(), 1};
  Plc right_{daemon_.port(), 2};
};

TEST_F(TwoEDrivesE2E, BothOnlineEachWithItsOwnData) {
  EXPECT_EQ(text(left_.input(ed::model, 8)), "EDRIVE-SIM-24V");
  // Serial numbers differ per id (SIM100000<id>): each unit shows its own drive.
  const auto serial = [](Plc& plc) { return text(plc.input(ed::model + 8, 8)); };
  EXPECT_EQ(serial(left_), "SIM1000001");
  EXPECT_EQ(serial(right_), "SIM1000002");
  ASSERT_EQ(right_.write(reg::command, {1, 3000}), 0);
  EXPECT_THAT(sim_.control("@2 state"), HasSubstr("target=3000"));
  EXPECT_THAT(sim_.control("@1 state"), HasSubstr("target=0"));
  EXPECT_EQ(left_.input(reg::speed, 1).regs[0], 0);
}

TEST_F(TwoEDrivesE2E, ASilentDriveKeepsTheOthersDataFresh) {
  const auto [age_both, frames_both] = watch_left(5s);
  ASSERT_THAT(sim_.control("@2 silent on"), HasSubstr("silent=on"));
  ASSERT_TRUE(
      eventually([&] { return (right_.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 8s));
  EXPECT_EQ(right_.input(reg::fault_code, 1).regs[0], kCommLost);
  const auto [age_silent, frames_silent] = watch_left(5s);
  RecordProperty("left_worst_age_ms_both_answering", static_cast<int>(age_both));
  RecordProperty("left_worst_age_ms_right_silent", static_cast<int>(age_silent));
  RecordProperty("left_frames_5s_both_answering", static_cast<int>(frames_both));
  RecordProperty("left_frames_5s_right_silent", static_cast<int>(frames_silent));
  std::cerr << "left drive over 5 s: both answering worst age " << age_both << " ms, "
            << frames_both << " frames; right silent worst age " << age_silent << " ms, "
            << frames_silent << " frames\n";
  EXPECT_LT(age_both, static_cast<std::uint32_t>(kPollMs + kBudgetMs));
  EXPECT_LT(age_silent, static_cast<std::uint32_t>(kPollMs + kBudgetMs));
  // Polled at least every poll interval + the silent one's budget, in both cases.
  EXPECT_GE(frames_silent, 5000u / (kPollMs + kBudgetMs));
  // The left one still takes writes while its neighbour is silent.
  EXPECT_EQ(left_.write(reg::command, {1, 3000}), 0);
  // The silent one answers again and comes back.
  sim_.control("@2 silent off");
  EXPECT_TRUE(comes_online(right_));
}

}  // namespace
}  // namespace drivegate::test::unicla_edrive_e2e_test
