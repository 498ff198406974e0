// mdriver-2400 end to end: the daemon drives the simulated compressor
// driver from Modbus TCP as a PLC would. The run frames on the line are taken from drivegated's
// trace log (sum of all bytes = 0x55, adapters/mdriver-2400/README.md "Frames").
#include "e2e.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <sstream>

#include "drive_e2e.h"
#include "e2e_adapters.h"
#include "protocol_adapters.h"
#include "trace_log.h"

namespace drivegate::test::mdriver_2400_e2e_test {
namespace {

// How the core's scenarios on every drive (tests/e2e: capture, status page) run this one.
const RegisterE2eAdapter kE2eAdapter({.id = "mdriver-2400",
                                      .rpm = 1149,
                                      .protocol = "MDRIVER-2400",
                                      .checksum_field = "mdriver2400.checksum.status"});

using namespace std::chrono_literals;
using ::testing::Contains;
using ::testing::HasSubstr;

constexpr const char* kBus = "compressor-line";

// Register map of this configuration (`drivegate regmap`): adapter points after the common block.
namespace md {
inline constexpr int target_code = 32, target_rpm = 33, actual_code = 34, error_code = 35,
                     ipm_temperature = 36, sent_code = 40, fixed_code_state = 41;
}  // namespace md

// Run frames `00 01 10 02 D4 D5 00 cs` (section 3 No.2), D5 = 01 normal mode.
constexpr const char* kRun1149 = "00 01 10 02 40 01 00 01";  // code 0x40 = 1149 rpm
constexpr const char* kStop = "00 01 10 02 01 01 00 40";     // code 0x01: stop
constexpr const char* kReset = "00 01 10 02 00 01 00 41";    // code 0x00: reset and stop

// The driver under the C++ adapter or the framed one with its description (protocol_adapters.h).
std::string config(const std::filesystem::path& port, int poll_ms, const ProtocolAdapter& a) {
  return "[[bus]]\nname = \"" + std::string(kBus) + "\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"compressor\"\nbus = \"" + kBus +
         "\"\nunit_id = 1\npoll_ms = " + std::to_string(poll_ms) + "\n" + device_adapter(a);
}

class MDriverE2E : public DriveE2E<::testing::TestWithParam<ProtocolAdapter>> {
 protected:
  explicit MDriverE2E(int poll_ms = 500)
      : DriveE2E(
            "mdriver-2400", "compressor", {},
            [=](const std::filesystem::path& port) { return config(port, poll_ms, GetParam()); },
            {"--log-level", "trace"}, "drivegated.log") {}
  std::vector<std::string> frames() { return wire().tx; }
  Wire wire() { return read_wire(dir_ / "drivegated.log", kBus); }
  std::uint16_t in(int address) { return plc_.input(address, 1).regs[0]; }
};

TEST_P(MDriverE2E, StartsWithTheFixedCodeCheck) {
  EXPECT_THAT(frames(), Contains("00 01 00 03 01 12 00 06 38"));  // section 3 No.1
  EXPECT_EQ(in(md::fixed_code_state), 1);                         // ok
  EXPECT_EQ(in(reg::fault_code), 0);
}

TEST_P(MDriverE2E, RunsAt1149RpmAsCode0x40AndReadsSpeedAndTemperatureBack) {
  EXPECT_THAT(sim_.control("temp 47"), HasSubstr("temp=47"));
  // Setpoint and command in one request: the setpoint applies first.
  ASSERT_EQ(plc_.write(reg::command, {1 /*run_forward*/, 1149}), 0);
  EXPECT_THAT(frames(), Contains(kRun1149));
  EXPECT_THAT(sim_.control("state"), HasSubstr("target=0x40"));
  ASSERT_TRUE(eventually([&] { return in(reg::speed) == 1149; }, 10s)) << sim_.control("state");
  const auto r = plc_.input(md::target_code, 10);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.regs[0], 0x40);  // target code, echoed by the driver
  EXPECT_EQ(r.regs[1], 1149);  // target rpm
  EXPECT_EQ(r.regs[2], 0x40);  // actual code
  EXPECT_EQ(r.regs[3], 0);     // no error
  ASSERT_TRUE(eventually([&] { return in(md::ipm_temperature) == 47; }));
  EXPECT_EQ(in(md::sent_code), 0x40);
  EXPECT_TRUE(in(reg::status)&reg::running);
  EXPECT_EQ(plc_.holding(reg::command, 2).regs, (std::vector<std::uint16_t>{1, 1149}));

  ASSERT_EQ(plc_.write(reg::command, {0 /*stop*/}), 0);
  EXPECT_THAT(frames(), Contains(kStop));
  ASSERT_TRUE(eventually([&] { return in(reg::speed) == 0; }, 10s)) << sim_.control("state");
}

TEST_P(MDriverE2E, OverTemperatureTripIsDriveOverTemperatureAndResetClearsIt) {
  ASSERT_EQ(plc_.write(reg::command, {1, 1149}), 0);
  EXPECT_THAT(sim_.control("fault ipm_over_temperature"), HasSubstr("ok"));
  ASSERT_TRUE(eventually([&] { return in(reg::fault_code) == 5; }, 5s))  // drive_over_temperature
      << sim_.control("state");
  const auto r = plc_.input(reg::status, 7);
  EXPECT_TRUE(r.regs[0] & reg::fault);
  EXPECT_EQ(r.u32(reg::fault_mask), 1u << 5);
  EXPECT_EQ(r.u32(reg::native_fault), 0x0Eu);  // ipm_over_temperature
  EXPECT_EQ(in(md::error_code), 0x0E);
  ASSERT_TRUE(eventually([&] { return in(reg::speed) == 0; }));  // an error stops the motor
  EXPECT_EQ(plc_.write(reg::command, {1}), 0x04);                // tripped: will not run

  ASSERT_EQ(plc_.write(reg::command, {4 /*reset_fault*/}), 0);
  EXPECT_THAT(frames(), Contains(kReset));
  ASSERT_TRUE(eventually([&] { return in(reg::fault_code) == 0; }, 5s)) << sim_.control("state");
  const auto after = plc_.input(reg::status, 7);
  EXPECT_FALSE(after.regs[0] & reg::fault);
  EXPECT_EQ(after.u32(reg::fault_mask), 0u);
  EXPECT_EQ(after.u32(reg::native_fault), 0u);
  EXPECT_EQ(plc_.holding(reg::command, 1).regs[0], 0);  // reset leaves it stopped
  EXPECT_THAT(sim_.control("state"), HasSubstr("error=0x00"));
  EXPECT_EQ(plc_.write(reg::command, {1}), 0);  // and it runs again
  ASSERT_TRUE(eventually([&] { return in(reg::speed) == 1149; }, 10s)) << sim_.control("state");
}

TEST_P(MDriverE2E, ReverseAndSpeedsOffTheTableAreIllegalValues) {
  EXPECT_EQ(plc_.write(reg::command, {2 /*run_reverse*/}), 0x03);  // one direction only
  EXPECT_EQ(plc_.write(reg::setpoint, {503}), 0x03);               // under the lowest running speed
  EXPECT_EQ(plc_.write(reg::setpoint, {0}), 0x03);
  EXPECT_EQ(plc_.write(reg::setpoint, {2857}), 0x03);  // above the table
  EXPECT_EQ(plc_.write(reg::setpoint, {504}), 0);      // 0x1C, the lowest running code
  ASSERT_EQ(plc_.write(reg::command, {1}), 0);
  EXPECT_THAT(frames(), Contains("00 01 10 02 1C 01 00 25"));  // section 3 No.2
}

TEST_P(MDriverE2E, FailedFixedCodeCheckIsHardwareFaultNotOnline) {
  // The driver forgets the check and answers the next one with zeros (section 3 No.1); run data
  // goes unanswered meanwhile, so the gateway declares comm_lost (6 s) and checks again.
  EXPECT_EQ(sim_.control("eeprom fail"), "ok eeprom=fail");
  ASSERT_TRUE(eventually([&] { return in(reg::fault_code) == 12; }, 15s))  // hardware_fault
      << sim_.control("state");
  EXPECT_THAT(frames(), Contains("00 01 00 03 01 12 00 06 38"));
  const auto r = plc_.input(reg::status, 7);
  EXPECT_FALSE(r.regs[0] & reg::online);
  EXPECT_TRUE(r.regs[0] & reg::fault);
  EXPECT_EQ(r.u32(reg::native_fault), 0x100u);
  EXPECT_EQ(in(md::fixed_code_state), 2);  // fixed_code_error
  // It answers, so not 0x0B: a driver that is not ready refuses (README "Commands and writes").
  EXPECT_EQ(plc_.write(reg::command, {1, 1149}), 0x04);

  EXPECT_EQ(sim_.control("eeprom ok"), "ok eeprom=ok");
  ASSERT_TRUE(eventually([&] { return (in(reg::status)&reg::online) != 0; }, 10s))
      << sim_.control("state");
  EXPECT_EQ(in(reg::fault_code), 0);
  EXPECT_EQ(in(md::fixed_code_state), 1);
}

// Polled only every 10 s, longer than the driver's 6 s trip: only the keep-alive can hold it.
class MDriverKeepAliveE2E : public MDriverE2E {
 protected:
  MDriverKeepAliveE2E() : MDriverE2E(10'000) {}
};

TEST_P(MDriverKeepAliveE2E, KeepsTheDriverRunningWellPast6sWithoutModbusTraffic) {
  ASSERT_EQ(plc_.write(reg::command, {1, 1149}), 0);
  const std::size_t before = wire().tx.size();
  std::this_thread::sleep_for(9s);  // no Modbus traffic
  EXPECT_THAT(sim_.control("state"), HasSubstr("target=0x40 change=0x01 actual=0x40"));
  EXPECT_THAT(sim_.control("state"), HasSubstr("error=0x00"));
  const Wire w = wire();
  long gap = 0;
  std::size_t runs = 0;
  for (std::size_t i = before; i < w.tx.size(); ++i) {
    EXPECT_EQ(w.tx[i], kRun1149);  // the current target, every time
    if (i > before) gap = std::max(gap, w.tx_ms[i] - w.tx_ms[i - 1]);
    ++runs;
  }
  EXPECT_GE(runs, 6u);    // keepalive_ms 1000 over 9 s
  EXPECT_LT(gap, 2'500);  // far under the 6 s trip
  RecordProperty("keepalive_frames", static_cast<int>(runs));
  RecordProperty("keepalive_max_gap_ms", static_cast<int>(gap));
  const auto r = plc_.input(reg::status, 7);
  EXPECT_TRUE(r.regs[0] & reg::online);
  EXPECT_TRUE(r.regs[0] & reg::running);
  EXPECT_EQ(r.regs[reg::fault_code], 0);
  EXPECT_EQ(r.regs[reg::speed], 1149);
}

INSTANTIATE_TEST_SUITE_P(, MDriverE2E, ::testing::ValuesIn(protocol_adapters("mdriver-2400")),
                         adapter_name);
INSTANTIATE_TEST_SUITE_P(, MDriverKeepAliveE2E,
                         ::testing::ValuesIn(protocol_adapters("mdriver-2400")), adapter_name);

}  // namespace
}  // namespace drivegate::test::mdriver_2400_e2e_test
