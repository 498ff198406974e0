// nidec-washer end to end: the daemon on a simulated one-wire line (with echo) at 4800 8O1,
// driven from Modbus TCP as a PLC would (issue: the gateway core, "Not done until").
#include "e2e.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "drive_e2e.h"
#include "e2e_adapters.h"
#include "protocol_adapters.h"

namespace drivegate::test {
namespace {

// How the core's scenarios on every drive (tests/e2e: capture, status page) run this one.
const RegisterE2eAdapter kE2eAdapter({.id = "nidec-washer",
                                      .device_extra = "[device.options]\nplatform = 8\n",
                                      .rpm = 800,
                                      .protocol = "NIDEC-WASHER",
                                      .checksum_field = "nidec_washer.checksum.status"});

using namespace std::chrono_literals;

// The washer under the C++ adapter or the framed one with its description (protocol_adapters.h).
std::string config(const std::filesystem::path& port, const ProtocolAdapter& a) {
  return "[[bus]]\nname = \"washer-line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"washer\"\nbus = \"washer-line\"\nunit_id = 1\n" +
         device_adapter(a, "platform = 8\n");
}

class NidecE2E : public DriveE2E<::testing::TestWithParam<ProtocolAdapter>> {
 protected:
  NidecE2E()
      : DriveE2E("nidec-washer", "washer", {},
                 [](const std::filesystem::path& port) { return config(port, GetParam()); }) {}
};

TEST_P(NidecE2E, RunsForwardReadsLiveSpeedAndStops) {
  // Setpoint and command in one request: the setpoint applies first.
  ASSERT_EQ(plc_.write(reg::command, {1 /*run_forward*/, 800}), 0);
  EXPECT_THAT(sim_.control("state"), ::testing::HasSubstr("platform=8"));
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::speed, 1).regs[0] == 800; }, 10s))
      << sim_.control("state");
  const auto status = plc_.input(reg::status, 19);
  ASSERT_TRUE(status.ok());
  EXPECT_TRUE(status.regs[0] & reg::running);
  EXPECT_LT(status.u32(reg::data_age), 1500u);  // polled every 500 ms
  EXPECT_GT(status.u32(reg::frames_good), 1u);
  const auto hr = plc_.holding(reg::command, 2);
  EXPECT_EQ(hr.regs[0], 1);
  EXPECT_EQ(hr.regs[1], 800);

  ASSERT_EQ(plc_.write(reg::command, {0 /*stop*/}), 0);
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::speed, 1).regs[0] == 0; }, 10s));
  EXPECT_EQ(plc_.holding(reg::command, 1).regs[0], 0);
}

TEST_P(NidecE2E, ReverseIsCounterClockwise) {
  ASSERT_EQ(plc_.write(reg::command, {2 /*run_reverse*/, 600}), 0);
  EXPECT_THAT(sim_.control("state"), ::testing::HasSubstr("motion=ccw"));
}

TEST_P(NidecE2E, NativeFaultBecomesUnifiedFault) {
  sim_.control("fault stall");
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::fault_code, 1).regs[0] == 7; }, 5s));
  const auto r = plc_.input(reg::status, 6);
  EXPECT_TRUE(r.regs[0] & reg::fault);
  EXPECT_EQ(r.u32(reg::fault_mask), 1u << 7);
  EXPECT_EQ(r.u32(reg::native_fault), 0x08u);
  // A drive that will not run says so: exception 0x04, not OK.
  EXPECT_EQ(plc_.write(reg::command, {1, 800}), 0x04);
}

TEST_P(NidecE2E, SilentDriveIsCommLostAndWritesGet0x0B) {
  sim_.control("silent on");
  const auto lost_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(
      eventually([&] { return (plc_.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 8s));
  EXPECT_LT(std::chrono::steady_clock::now() - lost_at, 7s);
  const auto r = plc_.input(reg::status, 19);
  EXPECT_FALSE(r.regs[0] & reg::online);
  EXPECT_EQ(r.regs[reg::fault_code], 1);  // comm_lost
  EXPECT_GT(r.u32(reg::timeouts), 0u);
  EXPECT_GE(r.u32(reg::data_age), 6000u);
  EXPECT_EQ(plc_.write(reg::command, {1, 800}), 0x0B);
  // It is still probed, and comes back by itself.
  sim_.control("silent off");
  ASSERT_TRUE(comes_online(plc_));
  EXPECT_EQ(plc_.write(reg::command, {1, 500}), 0);
}

TEST_P(NidecE2E, UnknownUnitAndBadWritesAreExceptions) {
  Plc other(daemon_.port(), 9);
  ASSERT_TRUE(other.connect());
  EXPECT_EQ(other.input(0, 1).exception, 0x0A);
  EXPECT_EQ(plc_.write(reg::command, {9}), 0x03);  // no such command
  EXPECT_EQ(plc_.write(3, {1}), 0x02);             // unmapped
  EXPECT_EQ(plc_.input(31, 1).exception, 0x02);    // reserved gap
}

TEST_P(NidecE2E, SigtermStopsTheRunningDriveThenExitsZero) {
  ASSERT_EQ(plc_.write(reg::command, {1, 800}), 0);
  ASSERT_THAT(sim_.control("state"), ::testing::HasSubstr("target_rpm=800"));
  EXPECT_EQ(daemon_.stop(), 0);
  EXPECT_THAT(sim_.control("state"), ::testing::HasSubstr("motion=stop"));
}

INSTANTIATE_TEST_SUITE_P(, NidecE2E, ::testing::ValuesIn(protocol_adapters("nidec-washer")),
                         adapter_name);

}  // namespace
}  // namespace drivegate::test
