// A profile's own write codes ([modbus] write_single_code, write_multiple_code): inverters whose
// 0x06 / 0x10 save every write to EEPROM offer 0x41 / 0x42 "without saving", of the same layout.
// On the real bus engine against the simulator (tests/support/adapter_bench.h): the frames the
// master sends carry the profile's codes, the echo confirms them, the exception (code | 0x80) is a
// refusal, and a profile naming a code that is neither the protocol's nor a user-defined one is
// refused with its line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <variant>
#include <vector>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "common_block.h"
#include "drivegate/crc.h"
#include "profile.h"
#include "profile_support.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;
using testing::ElementsAre;
using testing::HasSubstr;

// Holding 0 its control word, holding 1 its frequency in rpm, holding 4..5 a two-register
// parameter; input 16 its actual speed, input 17 its status (bit 0 running).
std::string inverter(const std::string& modbus) {
  return "[profile]\nname = \"inv\"\nsource = \"a test\"\n[modbus]\nmax_gap = 0\n" + modbus +
         "[[point]]\nname = \"control\"\ntable = \"holding\"\naddress = 0\ntype = \"u16\"\n"
         "access = \"operate\"\n"
         "[[point]]\nname = \"frequency\"\ntable = \"holding\"\naddress = 1\ntype = \"u16\"\n"
         "min = 0\nmax = 3000\naccess = \"operate\"\n"
         "[[point]]\nname = \"limit\"\ntable = \"holding\"\naddress = 4\ntype = \"u32\"\n"
         "access = \"operate\"\n"
         "[[point]]\nname = \"speed\"\ntable = \"input\"\naddress = 16\ntype = \"u16\"\n"
         "[[point]]\nname = \"status\"\ntable = \"input\"\naddress = 17\ntype = \"u16\"\n"
         "[common]\nspeed_rpm = \"speed\"\nsetpoint_rpm = \"frequency\"\n"
         "running = { point = \"status\", bit = 0 }\n"
         "stop = { point = \"control\", value = 0 }\n"
         "run_forward = { point = \"control\", value = 1 }\n";
}

constexpr std::string_view kUnsaved = "write_single_code = 0x41\nwrite_multiple_code = 0x42\n";

// The RTU frame to unit 1: the PDU and its CRC, low byte first (Serial Line 6.2.2).
Bytes rtu(Bytes pdu) {
  pdu.insert(pdu.begin(), 0x01);
  const std::uint16_t crc = crc16_modbus(pdu);
  pdu.push_back(static_cast<std::uint8_t>(crc & 0xFF));
  pdu.push_back(static_cast<std::uint8_t>(crc >> 8));
  return pdu;
}

TEST(ModbusWriteCodes, WritesGoWithTheProfilesCodesAndTheirEchoConfirmsThem) {
  const support::ProfileFile file(inverter(std::string(kUnsaved)), "inv.toml");
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};
  ASSERT_TRUE(b.until_online());
  TimePoint from = b.rig.now();
  ASSERT_EQ(b.write({1200}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.count(rtu({0x41, 0x00, 0x01, 0x04, 0xB0}), from), 1u);
  EXPECT_EQ(b.count(rtu({0x41, 0x00, 0x00, 0x00, 0x01}), from), 1u);
  EXPECT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 1200u; }, 2s));
  // Two registers: the multiple code, FC 16's layout.
  from = b.rig.now();
  ASSERT_EQ(b.write_point("limit", 70000), Outcome::ok);
  EXPECT_EQ(b.count(rtu({0x42, 0x00, 0x04, 0x00, 0x02, 0x04, 0x00, 0x01, 0x11, 0x70}), from), 1u);
  EXPECT_EQ(b.read("limit"), 70000u);
  // Nothing went with the saving codes.
  for (const Bytes& f : b.frames()) {
    EXPECT_NE(f[1], 0x06);
    EXPECT_NE(f[1], 0x10);
  }
}

// The slave's exception to the profile's code (0xC1) is its refusal: exception 04 to the PLC, and
// the setpoint in force stays.
TEST(ModbusWriteCodes, AnExceptionToTheProfilesCodeIsARefusal) {
  const support::ProfileFile file(inverter(std::string(kUnsaved)), "inv.toml");
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.write({900}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(b.control("refuse holding 1 4 1").rfind("ok", 0), 0u);
  EXPECT_EQ(b.write({1500}, kSetpointRegister), Outcome::refused);
  EXPECT_EQ(b.read("setpoint_rpm"), 900u);
}

std::vector<std::string> code_errors_of(const std::string& modbus) {
  auto parsed = parse_profile(inverter(modbus), "p.toml");
  if (std::holds_alternative<Profile>(parsed)) return {};
  return std::get<std::vector<std::string>>(parsed);
}

TEST(ModbusWriteCodes, ACodeIsTheProtocolsOwnOrAUserDefinedOne) {
  EXPECT_TRUE(code_errors_of(std::string(kUnsaved)).empty());
  EXPECT_TRUE(code_errors_of("write_single_code = 6\nwrite_multiple_code = 16\n").empty());
  EXPECT_TRUE(code_errors_of("write_single_code = 100\nwrite_multiple_code = 110\n").empty());
  EXPECT_THAT(code_errors_of("write_single_code = 0x07\n"),
              ElementsAre(HasSubstr("p.toml:6: modbus.write_single_code: must be 6 or a "
                                    "user-defined function code (65..72, 100..110")));
  EXPECT_THAT(code_errors_of("write_multiple_code = 6\n"),
              ElementsAre(HasSubstr("modbus.write_multiple_code: must be 16 or a user-defined")));
  EXPECT_THAT(code_errors_of("write_single_code = 0xC1\n"),
              ElementsAre(HasSubstr("modbus.write_single_code")));
  const Profile p = std::get<Profile>(parse_profile(inverter(std::string(kUnsaved)), "p.toml"));
  EXPECT_EQ(p.modbus.write_single_code, 0x41);
  EXPECT_EQ(p.modbus.write_multiple_code, 0x42);
}

}  // namespace
}  // namespace drivegate::modbus_device
