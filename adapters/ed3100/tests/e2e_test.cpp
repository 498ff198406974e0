// ed3100 end to end: the daemon with an ED3100 at address 31 on a
// 9600 8E1 line, the simulator answering as the document's examples do, driven from Modbus TCP
// as a PLC would. The frames on the line are taken from drivegated's trace log and compared with
// the frames the document prints (adapters/ed3100/README.md, "Golden vectors").
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <sstream>

#include "drive_e2e.h"
#include "e2e.h"
#include "e2e_adapters.h"
#include "trace_log.h"

namespace drivegate::test {
namespace {

// How the core's scenarios on every drive (tests/e2e: capture, status page) run this one:
// 9600 8E1 at address 31, reading parameter block 00-06 as well.
const RegisterE2eAdapter kE2eAdapter(
    {.id = "ed3100",
     .bus_extra = "baud = 9600\nparity = \"even\"\ndata_bits = 8\nstop_bits = 1\n",
     .device_extra = "address = 31\n[device.options]\nparameters = [\"00-06\"]\n",
     .sim_args = {"--address", "31"},
     .rpm = 1500,
     .protocol = "ED3100",
     .checksum_field = "ed3100.crc.status"});

using namespace std::chrono_literals;
using ::testing::Contains;
using ::testing::HasSubstr;

constexpr const char* kBus = "ed-line";

// Register map of this configuration (`drivegate regmap`): adapter points after the common block.
namespace ed {
inline constexpr int drive_fault_code = 32, state_word = 33, running = 34, direction = 35;
inline constexpr int monitor_0d00 = 39, monitor_0d00_raw = 41, monitor_0d00_format = 42;
inline constexpr int frequency_setpoint = 16, param_00_06 = 17;  // holding
}  // namespace ed

std::string config(const std::filesystem::path& port) {
  return "[[bus]]\nname = \"" + std::string(kBus) + "\"\nport = \"" + port.string() +
         "\"\nbaud = 9600\nparity = \"even\"\ndata_bits = 8\nstop_bits = 1\n\n"
         "[[device]]\nname = \"ed\"\nbus = \"" +
         kBus +
         "\"\nadapter = \"ed3100\"\n"
         "unit_id = 1\naddress = 31\n[device.options]\nparameters = [\"00-06\"]\n";
}

float f32(const Plc::Read& r, std::size_t at) {
  return std::bit_cast<float>(r.u32(at));
}
std::int16_t i16(std::uint16_t v) {
  return static_cast<std::int16_t>(v);
}

class Ed3100E2E : public DriveE2E<> {
 protected:
  Ed3100E2E()
      : DriveE2E("ed3100", "ed", {"--address", "31"}, config, {"--log-level", "trace"},
                 "drivegated.log") {}
  Wire frames() { return read_wire(dir_ / "drivegated.log", kBus); }
  // True once `frame` has been sent (and, if given, `reply` received) on the line.
  bool seen(const std::string& frame, const std::string& reply = "") {
    const Wire w = frames();
    return std::find(w.tx.begin(), w.tx.end(), frame) != w.tx.end() &&
           w.rx.find(reply) != std::string::npos;
  }
  std::int16_t speed() { return i16(plc_.input(reg::speed, 1).regs[0]); }
};

TEST_F(Ed3100E2E, ReadsTheOutputFrequencyInTheDocumentsOwnFrames) {
  // Document: monitor 0D00 -> 0x1084 with format 0x4148 (two decimals, Hz, stopped) = 42.28 Hz.
  ASSERT_TRUE(
      eventually([&] { return plc_.input(ed::monitor_0d00_raw, 1).regs[0] == 0x1084; }, 5s));
  const auto m = plc_.input(ed::monitor_0d00, 4);
  ASSERT_TRUE(m.ok());
  EXPECT_FLOAT_EQ(f32(m, 0), 42.28f);
  EXPECT_EQ(m.regs[2], 0x1084);
  EXPECT_EQ(m.regs[3], 0x4148);
  EXPECT_EQ(speed(), 0);  // the stopped bit: the reference on display, the motor does not turn
  const auto st = plc_.input(ed::drive_fault_code, 3);
  EXPECT_EQ(st.regs[0], 0xFFFF);  // no fault
  EXPECT_EQ(st.regs[1], 0x0148);
  EXPECT_EQ(st.regs[2], 0);  // not running
  EXPECT_EQ(plc_.input(reg::fault_code, 1).regs[0], 0);

  // The exact frames the document prints, at address 0x1F, replies in the document's form.
  const Wire w = frames();
  EXPECT_THAT(w.tx, Contains("1F 03 00 06 00 01 67 B5"));  // parameter 00-06
  EXPECT_THAT(w.rx, HasSubstr("1F 03 00 06 10 88 AB D3"));
  EXPECT_THAT(w.tx, Contains("1F 03 0E 01 00 00 15 5C"));  // fault + state
  EXPECT_THAT(w.rx, HasSubstr("1F 03 0E 01 FF FF 01 48 0F 2B"));
  EXPECT_THAT(w.tx, Contains("1F 03 0D 00 00 00 44 D8"));  // output frequency monitor
  EXPECT_THAT(w.rx, HasSubstr("1F 03 0D 00 10 84 41 48 47 D5"));
  const auto status = plc_.input(reg::status, 19);
  EXPECT_EQ(status.u32(reg::bad_checksum), 0u);
  EXPECT_EQ(status.u32(reg::nacks), 0u);
}

TEST_F(Ed3100E2E, RunsForwardAndReverseFromModbusTcp) {
  // 42.32 Hz, the reference of the document's run examples (0x1088).
  ASSERT_EQ(plc_.write(ed::frequency_setpoint, {4232}), 0);
  EXPECT_EQ(i16(plc_.holding(reg::setpoint, 1).regs[0]), 1270);  // 42.32 x 120 / 4 poles

  ASSERT_EQ(plc_.write(reg::command, {1 /*run_forward*/}), 0);
  EXPECT_TRUE(seen("1F 10 20 00 00 02 04 00 1E 10 88 67 E6", "1F 10 20 00 00 02 49 B6"));
  EXPECT_THAT(sim_.control("state"), HasSubstr("command=0x001E reference=0x1088"));
  ASSERT_TRUE(eventually([&] { return speed() == 1270; }, 10s)) << sim_.control("state");
  auto st = plc_.input(ed::drive_fault_code, 4);
  EXPECT_EQ(st.regs[2], 1);  // running
  EXPECT_EQ(st.regs[3], 0);  // forward
  EXPECT_TRUE(plc_.input(reg::status, 1).regs[0] & reg::running);
  EXPECT_EQ(plc_.holding(reg::command, 1).regs[0], 1);

  ASSERT_EQ(plc_.write(reg::command, {2 /*run_reverse*/}), 0);
  EXPECT_TRUE(seen("1F 10 20 00 00 02 04 00 2E 10 88 67 E9"));
  ASSERT_TRUE(eventually([&] { return speed() == -1270; }, 10s)) << sim_.control("state");
  st = plc_.input(ed::drive_fault_code, 4);
  EXPECT_EQ(st.regs[2], 1);  // running
  EXPECT_EQ(st.regs[3], 1);  // reverse
  EXPECT_EQ(plc_.holding(reg::command, 1).regs[0], 2);

  ASSERT_EQ(plc_.write(reg::command, {0 /*stop*/}), 0);
  EXPECT_TRUE(seen("1F 06 20 00 00 01 40 74", "1F 06 20 00 00 01 40 74"));  // echo
  ASSERT_TRUE(eventually([&] { return speed() == 0; }, 10s)) << sim_.control("state");
  EXPECT_EQ(plc_.input(ed::running, 1).regs[0], 0);
  EXPECT_FALSE(plc_.input(reg::status, 1).regs[0] & reg::running);
}

TEST_F(Ed3100E2E, ReadsAndWritesAParameter) {
  ASSERT_TRUE(eventually([&] { return plc_.holding(ed::param_00_06, 1).regs[0] == 0x1088; }, 5s));
  ASSERT_EQ(plc_.write(ed::param_00_06, {0x1388}), 0);
  EXPECT_TRUE(seen("1F 06 00 06 13 88 67 23", "1F 06 00 06 13 88 67 23"));  // document: ask = echo
  EXPECT_THAT(sim_.control("state"), HasSubstr("param_00_06=0x1388"));
  EXPECT_EQ(plc_.holding(ed::param_00_06, 1).regs[0], 0x1388);
  // Read back after the write: a second 03 for 00-06, answered with the new value.
  ASSERT_TRUE(eventually([&] {
    const Wire w = frames();
    return std::count(w.tx.begin(), w.tx.end(), "1F 03 00 06 00 01 67 B5") >= 2 &&
           w.rx.find("1F 03 00 06 13 88") != std::string::npos;
  }));
  EXPECT_EQ(plc_.holding(ed::param_00_06, 1).regs[0], 0x1388);
}

TEST_F(Ed3100E2E, AlsoReadsTheStandardReplyForm) {
  EXPECT_EQ(sim_.control("form standard"), "ok form=standard");
  ASSERT_TRUE(eventually([&] {  // byte count 04 where the document echoes the register
    return frames().rx.find("1F 03 04 10 84 41 48 70 BD") != std::string::npos;
  }));
  const auto good = plc_.input(reg::status, 19).u32(reg::frames_good);
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::status, 19).u32(reg::frames_good) > good; }));
  const auto r = plc_.input(reg::status, 19);
  EXPECT_TRUE(r.regs[0] & reg::online);
  EXPECT_EQ(r.u32(reg::bad_checksum), 0u);
  EXPECT_EQ(plc_.input(ed::monitor_0d00_raw, 1).regs[0], 0x1084);
}

TEST_F(Ed3100E2E, CorruptReplyIsCountedAndTheSameFrameResent) {
  EXPECT_EQ(sim_.control("corrupt 1"), "ok corrupt=1");
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::status, 19).u32(reg::bad_checksum) == 1; }));
  const auto r = plc_.input(reg::status, 19);
  EXPECT_GE(r.u32(reg::retries), 1u);
  EXPECT_TRUE(r.regs[0] & reg::online);  // one bad CRC is not a lost drive
  EXPECT_EQ(r.regs[reg::fault_code], 0);
}

TEST_F(Ed3100E2E, SilentDriveIsCommLostWritesGet0x0BAndItComesBack) {
  EXPECT_EQ(sim_.control("silent on"), "ok silent=on");
  const auto lost_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(
      eventually([&] { return (plc_.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 8s));
  EXPECT_LT(std::chrono::steady_clock::now() - lost_at, 6s);  // comm_timeout_ms 3000
  const auto r = plc_.input(reg::status, 19);
  EXPECT_FALSE(r.regs[0] & reg::online);
  EXPECT_EQ(r.regs[reg::fault_code], 1);  // comm_lost
  EXPECT_GT(r.u32(reg::timeouts), 0u);
  EXPECT_GE(r.u32(reg::data_age), 3000u);
  EXPECT_EQ(plc_.write(reg::command, {1}), 0x0B);
  EXPECT_EQ(plc_.write(ed::param_00_06, {1}), 0x0B);

  EXPECT_EQ(sim_.control("silent off"), "ok silent=off");
  ASSERT_TRUE(comes_online(plc_));
  EXPECT_EQ(plc_.input(reg::fault_code, 1).regs[0], 0);
  EXPECT_EQ(plc_.holding(ed::param_00_06, 1).regs[0], 0x1088);  // read again on reconnect
  EXPECT_EQ(plc_.write(ed::frequency_setpoint, {4232}), 0);
  EXPECT_EQ(plc_.write(reg::command, {1}), 0);
  EXPECT_THAT(sim_.control("state"), HasSubstr("running=1"));
}

}  // namespace
}  // namespace drivegate::test
