// fdc1 end to end: the daemon on a simulated FDC1 controller (a streaming device, 1200 8N1), driven
// from Modbus TCP as a PLC would, and `drivegate action ... program` on
// the same simulator with the daemon not running.
#include "e2e.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "drive_e2e.h"
#include "e2e_adapters.h"
#include "protocol_adapters.h"

namespace drivegate::test::fdc1_e2e_test {
namespace {

// How the core's scenarios on every drive (tests/e2e: capture, status page) run this one:
// in slave mode (it answers each speed frame; refreshed every second).
const RegisterE2eAdapter kE2eAdapter(
    {.id = "fdc1",
     .device_extra = "[device.options]\nslave_mode = true\nrefresh_s = 1\n",
     .sim_args = {"--set", "slave_mode=true"},
     .rpm = 2000,
     .protocol = "FDC1",
     .checksum_field = "fdc1.checksum.status"});

using namespace std::chrono_literals;
using ::testing::HasSubstr;

// The adapter's input points after the common block (`drivegate regmap`, adapters/fdc1/points.cpp).
namespace fdc1 {
inline constexpr int motor_on = 32, current_a = 33, restart_s = 34, alarm_code = 35,
                     alarm_latched = 36, sent_speed_rpm = 37;
}  // namespace fdc1

// Unified fault codes (include/drivegate/common.h) the FDC1's alarm ranges map to.
inline constexpr std::uint16_t kCommLost = 1, kStall = 7, kOverload = 9, kSupplyFault = 10;

// Refresh every 2 s against a simulator whose watchdog is shortened to 5 s, so "past the 60 s
// window" takes seconds: the same ratio problem, scaled down.
constexpr int kRefreshS = 2;
constexpr int kWindowS = 5;
constexpr int kStaleMs = 2000;

// The controller under the C++ adapter (the default) or the framed one with its description
// (protocol_adapters.h).
std::string config(const std::filesystem::path& port, bool slave = true,
                   const ProtocolAdapter& a = {"fdc1", ""}) {
  return "[[bus]]\nname = \"fdc1-line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"fridge\"\nbus = \"fdc1-line\"\nunit_id = 1\n" +
         device_adapter(a, std::string("slave_mode = ") + (slave ? "true" : "false") +
                               "\nrefresh_s = " + std::to_string(kRefreshS) +
                               "\nstale_ms = " + std::to_string(kStaleMs) + "\n");
}

// The number after `key=` in the simulator's `state` line, or -1.
long field(const std::string& state, const std::string& key) {
  const std::string padded = " " + state;
  const auto at = padded.find(" " + key + "=");
  if (at == std::string::npos) return -1;
  return std::stol(padded.substr(at + key.size() + 2));
}

class Fdc1E2E : public DriveE2E<::testing::TestWithParam<ProtocolAdapter>> {
 protected:
  Fdc1E2E()
      : DriveE2E("fdc1", "fdc1", {"--set", "slave_mode=true"},
                 [](const std::filesystem::path& port) { return config(port, true, GetParam()); }) {
  }
  void SetUp() override {
    ASSERT_EQ(sim_.control("window " + std::to_string(kWindowS)), "ok");
    DriveE2E::SetUp();
  }
  void run_at_2000() {
    ASSERT_EQ(plc_.write(reg::command, {1 /*run_forward*/, 2000}), 0) << state();
    ASSERT_TRUE(eventually([&] { return plc_.input(reg::speed, 1).regs[0] == 2000; }, 10s))
        << state();
  }
};

TEST_P(Fdc1E2E, RunsAt2000InSlaveModePastTheRefreshWindow) {
  run_at_2000();
  EXPECT_THAT(state(), HasSubstr("min=2000 max=2000"));  // slave: minimum = maximum = setpoint
  const auto in = plc_.input(fdc1::motor_on, 6);
  ASSERT_TRUE(in.ok());
  EXPECT_EQ(in.regs[0], 1);     // motor_on
  EXPECT_EQ(in.regs[1], 2400);  // 2000 rpm x 0.0012 A/rpm, in mA
  EXPECT_EQ(in.regs[fdc1::sent_speed_rpm - fdc1::motor_on], 2000);

  // Three windows long: without the refresh the controller would have stopped twice over.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(3 * kWindowS);
  long worst_age_ms = 0;
  int samples = 0;
  while (std::chrono::steady_clock::now() < until) {
    const std::string s = state();
    ASSERT_THAT(s, HasSubstr("motor=on rpm=2000")) << "stopped after " << samples << " samples";
    ASSERT_THAT(s, HasSubstr("watchdog=0"));
    worst_age_ms = std::max(worst_age_ms, field(s, "speed_age_ms"));
    const auto r = plc_.input(reg::status, 9);
    ASSERT_TRUE(r.ok());
    ASSERT_TRUE(r.regs[0] & reg::running);
    ASSERT_EQ(r.regs[reg::speed], 2000);
    ASSERT_LT(r.u32(reg::data_age), 1500u);  // streamed every 500 ms
    ++samples;
    std::this_thread::sleep_for(250ms);
  }
  // The frame is repeated every refresh_s, well inside the window.
  EXPECT_LT(worst_age_ms, kRefreshS * 1000 + 1000) << "slowest refresh";
  EXPECT_GE(field(state(), "speeds"), 3 * kWindowS / kRefreshS) << state();
  RecordProperty("worst_speed_age_ms", static_cast<int>(worst_age_ms));

  // The window is real: with the gateway gone (no stop sent) the controller stops by itself.
  ASSERT_EQ(daemon_.process().stop(SIGKILL), 128 + SIGKILL);
  EXPECT_TRUE(eventually([&] { return state().find("watchdog=1") != std::string::npos; },
                         std::chrono::seconds(kWindowS + 3)));
  EXPECT_THAT(state(), HasSubstr("motor=off"));
}

TEST_P(Fdc1E2E, StopProgramsZeroAndTheStreamConfirmsIt) {
  run_at_2000();
  ASSERT_EQ(plc_.write(reg::command, {0 /*stop*/}), 0);
  EXPECT_THAT(state(), HasSubstr("motor=off"));  // the reply waited for the OFF form
  EXPECT_THAT(state(), HasSubstr("min=0 max=3500"));
  EXPECT_EQ(plc_.input(reg::speed, 1).regs[0], 0);
  EXPECT_EQ(plc_.input(fdc1::sent_speed_rpm, 1).regs[0], 0);
}

TEST_P(Fdc1E2E, AlarmIsAUnifiedFaultWithItsRawCode) {
  run_at_2000();
  sim_.control("fault start");  // 48: motor failed to start
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::fault_code, 1).regs[0] == kStall; }, 5s))
      << state();
  auto r = plc_.input(reg::status, 6);
  EXPECT_TRUE(r.regs[0] & reg::fault);
  EXPECT_EQ(r.u32(reg::fault_mask), 1u << kStall);
  EXPECT_EQ(r.u32(reg::native_fault), 48u);
  EXPECT_EQ(plc_.input(fdc1::alarm_code, 2).regs, (std::vector<std::uint16_t>{48, 0}));

  sim_.control("fault overload_eor");  // 192: motor overload, end of retries
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::native_fault, 2).u32(0) == 192u; }, 5s));
  r = plc_.input(reg::status, 6);
  EXPECT_EQ(r.regs[reg::fault_code], kOverload);
  EXPECT_EQ(r.u32(reg::fault_mask), 1u << kOverload);
  EXPECT_EQ(plc_.input(fdc1::alarm_code, 2).regs, (std::vector<std::uint16_t>{192, 1}));

  sim_.control("fault 0x13");  // battery out of limits, a code inside its range
  ASSERT_TRUE(
      eventually([&] { return plc_.input(reg::fault_code, 1).regs[0] == kSupplyFault; }, 5s));
  EXPECT_EQ(plc_.input(reg::native_fault, 2).u32(0), 0x13u);

  // A run asked for while the controller reports an alarm is refused (0x04), not OK.
  ASSERT_EQ(plc_.write(reg::command, {0 /*stop*/}), 0);
  EXPECT_EQ(plc_.write(reg::command, {1, 2000}), 0x04);

  sim_.control("clear");
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::fault_code, 1).regs[0] == 0; }, 5s));
  r = plc_.input(reg::status, 6);
  EXPECT_FALSE(r.regs[0] & reg::fault);
  EXPECT_EQ(r.u32(reg::fault_mask), 0u);
  EXPECT_EQ(r.u32(reg::native_fault), 0u);
  // The refused run did not stay in force: cleared, the controller stays off until asked.
  std::this_thread::sleep_for(1500ms);
  EXPECT_EQ(plc_.holding(reg::command, 1).regs[0], 0);
  EXPECT_EQ(plc_.input(reg::speed, 1).regs[0], 0);
  run_at_2000();
}

TEST_P(Fdc1E2E, SpeedsOutsideTheRangeAndReverseAre0x03) {
  // In slave mode the driver sends the order in force (stop) once it is ready: counted from
  // after that frame, or it races the refused writes below (seen under TSan).
  ASSERT_TRUE(eventually([&] { return field(state(), "speeds") >= 1; }, 5s))
      << "the start-up stop order never went out: " << state();
  const long speeds_before = field(state(), "speeds");
  EXPECT_EQ(plc_.write(reg::setpoint, {1499}), 0x03);
  EXPECT_EQ(plc_.write(reg::setpoint, {3501}), 0x03);
  EXPECT_EQ(plc_.write(reg::setpoint, {0}), 0x03);
  EXPECT_EQ(plc_.write(reg::command, {1, 1000}), 0x03);
  EXPECT_EQ(plc_.write(reg::command, {1, 4000}), 0x03);
  EXPECT_EQ(plc_.write(reg::command, {2 /*run_reverse*/, 2000}), 0x03);
  EXPECT_EQ(plc_.write(reg::command, {4 /*reset_fault*/}), 0x03);
  // Nothing reached the line, and the controller still idles.
  const std::string s = state();
  EXPECT_EQ(field(s, "speeds"), speeds_before) << s;
  EXPECT_EQ(field(s, "rejected"), 0) << s;
  EXPECT_THAT(s, HasSubstr("motor=off"));
  // The bounds themselves are accepted.
  EXPECT_EQ(plc_.write(reg::setpoint, {1500}), 0);
  EXPECT_EQ(plc_.write(reg::setpoint, {3500}), 0);
  EXPECT_EQ(plc_.holding(reg::setpoint, 1).regs[0], 3500);
}

TEST_P(Fdc1E2E, CommLostAfterStaleMsWhenTheStreamStops) {
  run_at_2000();
  sim_.control("silent on");
  const auto silent_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(
      eventually([&] { return (plc_.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 8s));
  const auto took = std::chrono::steady_clock::now() - silent_at;
  EXPECT_GE(took, std::chrono::milliseconds(kStaleMs - 500));  // the last frame was < 0.5 s old
  EXPECT_LT(took, std::chrono::milliseconds(kStaleMs + 1500));
  RecordProperty(
      "comm_lost_after_ms",
      static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(took).count()));
  const auto r = plc_.input(reg::status, 19);
  EXPECT_FALSE(r.regs[0] & reg::online);
  EXPECT_EQ(r.regs[reg::fault_code], kCommLost);
  EXPECT_GE(r.u32(reg::data_age), static_cast<std::uint32_t>(kStaleMs));
  EXPECT_EQ(plc_.write(reg::command, {1, 2500}), 0x0B);

  // The stream returns: online again, and the run in force is sent again at once.
  sim_.control("silent off");
  ASSERT_TRUE(comes_online(plc_, 5s));
  EXPECT_EQ(plc_.input(reg::fault_code, 1).regs[0], 0);
}

// A reload that adds a compressor on another line leaves the running one alone: its bus and
// device move over as they run. A fresh device would begin with a start-up that asserts stop,
// so the compressor would stop within a stream period (0.5 s).
TEST_P(Fdc1E2E, AReloadAddingALineLeavesTheRunningCompressorAlone) {
  run_at_2000();
  Sim freezer("fdc1", dir_ / "fdc1-b", {"--set", "slave_mode=true"});
  std::ofstream(daemon_.config())
      << config(dir_ / "fdc1", true, GetParam()) << "\n[[bus]]\nname = \"line-b\"\nport = \""
      << (dir_ / "fdc1-b").string()
      << "\"\n\n[[device]]\nname = \"freezer\"\nbus = \"line-b\"\nadapter = \"fdc1\"\n"
         "unit_id = 2\n[device.options]\nslave_mode = true\n";
  daemon_.process().signal(SIGHUP);
  plc_.unit(2);
  ASSERT_TRUE(comes_online(plc_)) << "the added compressor never came online";

  plc_.unit(1);
  const auto until = std::chrono::steady_clock::now() + 2s;  // four stream periods
  while (std::chrono::steady_clock::now() < until) {
    ASSERT_NE(state().find("motor=on"), std::string::npos) << state();
    const auto command = plc_.holding(reg::command, 2);
    ASSERT_TRUE(command.ok());
    EXPECT_EQ(command.regs[0], 1);  // run_forward still in force
    EXPECT_EQ(command.regs[1], 2000);
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_EQ(plc_.input(reg::speed, 1).regs[0], 2000);
}

TEST_P(Fdc1E2E, NoiseAndBadChecksumsCostFramesNotTheLink) {
  const auto before = plc_.input(reg::status, 19);
  sim_.control("noise 20");
  sim_.control("corrupt 3");
  ASSERT_TRUE(eventually([&] { return field(state(), "corrupt") == 0; }, 5s));
  ASSERT_TRUE(eventually(
      [&] {
        return plc_.input(reg::status, 19).u32(reg::bad_checksum) >=
               before.u32(reg::bad_checksum) + 3;
      },
      5s));
  // Three bad frames are 1.5 s without a good one: under stale_ms, so the link holds.
  auto after = plc_.input(reg::status, 19);
  EXPECT_TRUE(after.regs[0] & reg::online);
  EXPECT_FALSE(after.regs[0] & reg::comm_lost);
  EXPECT_TRUE(eventually(
      [&] {
        after = plc_.input(reg::status, 19);
        return after.u32(reg::frames_good) > before.u32(reg::frames_good);
      },
      2s));
  EXPECT_LT(after.u32(reg::data_age), 1000u);
}

INSTANTIATE_TEST_SUITE_P(, Fdc1E2E, ::testing::ValuesIn(protocol_adapters("fdc1")), adapter_name);

// `drivegate action ... program` (the adapter's maintenance action) with the daemon NOT running:
// the CLI owns the line.
class Fdc1ProgramE2E : public ::testing::Test {
 protected:
  Fdc1ProgramE2E() : sim_("fdc1", dir_ / "fdc1") {
    std::ofstream(dir_ / "drivegate.toml") << config(dir_ / "fdc1", /*slave=*/false);
  }
  // Runs the CLI to its end; returns its exit status and stdout.
  std::pair<int, std::string> program(std::vector<std::string> settings) {
    std::vector<std::string> argv = {(bin_dir() / "drivegate").string(),
                                     "action",
                                     "--config",
                                     (dir_ / "drivegate.toml").string(),
                                     "--device",
                                     "fridge",
                                     "--plugin-dir",
                                     plugin_dir().string(),
                                     "program"};
    argv.insert(argv.end(), settings.begin(), settings.end());
    Child cli(argv);
    std::string out;
    while (auto line = cli.read_line(30s)) out += *line + "\n";
    EXPECT_TRUE(eventually([&] { return !cli.running(); }, 10s));
    return {cli.stop(), out};
  }
  TempDir dir_;
  Sim sim_;
};

// The README's standard example: 2000..3000 rpm, slave mode, 10.5/12.5, 21/25, 36/44 V.
std::vector<std::string> standard(std::string cut_out_12v) {
  return {"min_rpm=2000",    "max_rpm=3000",   "mode=2",        "cut_out_12v=" + cut_out_12v,
          "cut_in_12v=12.5", "cut_out_24v=21", "cut_in_24v=25", "cut_out_42v=36",
          "cut_in_42v=44"};
}

TEST_F(Fdc1ProgramE2E, AValidProgramIsConfirmedByTheEcho) {
  ASSERT_THAT(sim_.control("state"), HasSubstr("programs=0"));
  const auto [status, out] = program(standard("10.5"));
  EXPECT_EQ(status, 0) << out;
  EXPECT_THAT(out, HasSubstr("prog_commit=1: ok"));
  const std::string s = sim_.control("state");
  EXPECT_THAT(s, HasSubstr("programs=1"));
  EXPECT_THAT(s, HasSubstr("mode=2 slave=1"));  // the controller applied the stored mode
}

TEST_F(Fdc1ProgramE2E, CutOutNotBelowCutInIsRefusedBeforeAnythingIsSent) {
  const auto [status, out] = program(standard("13"));  // 13 V >= cut-in 12.5 V
  EXPECT_EQ(status, 1) << out;
  EXPECT_THAT(out, HasSubstr("prog_commit=1: value refused (0x03)"));
  // The rule, named (adapters/fdc1/program.cpp via the prog_message point).
  EXPECT_THAT(out, HasSubstr("cut_out_12v 13.00 V must be below cut_in_12v 12.50 V"));
  const std::string s = sim_.control("state");
  EXPECT_THAT(s, HasSubstr("programs=0"));
  EXPECT_THAT(s, HasSubstr("rejected=0"));
  EXPECT_THAT(s, HasSubstr("mode=0 slave=0"));
}

}  // namespace
}  // namespace drivegate::test::fdc1_e2e_test
