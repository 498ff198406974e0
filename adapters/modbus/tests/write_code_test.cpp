// A point's own write code (point.write_code): inverters whose 0x06 saves every write to EEPROM
// offer 0x41 "without saving", of the same layout (docs/profiles.md, "Writes that are not
// saved"). On the real bus engine against the simulator (tests/support/adapter_bench.h):
// the frames on the wire carry the point's code and only its; the echo confirms a write whether
// the drive answers under the code sent or under the one it is laid out as; an echo that holds a
// good CRC before its end is still taken whole; an exception under either code is a refusal; a
// reply under any other code is not the write's; and a profile that names a code wrongly is
// refused with its line.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "common_block.h"
#include "drivegate/crc.h"
#include "profile.h"
#include "profile_examples.h"
#include "profile_support.h"
#include "simulator.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;
using testing::ElementsAre;
using testing::HasSubstr;

// Holding 0 its command word (FC 06), holding 1 its frequency (rpm, written with `code`),
// holding 4..5 a two-register limit (FC 16; `code2` added to it); input 16 its actual speed,
// input 17 its status (bit 0 running).
std::string unsaved_inverter(const std::string& code, const std::string& code2 = "",
                             const std::string& extra = "") {
  return "[profile]\nname = \"inv\"\nsource = \"a test\"\n[modbus]\nmax_gap = 0\n"
         "[[point]]\nname = \"control\"\ntable = \"holding\"\naddress = 0\ntype = \"u16\"\n"
         "access = \"operate\"\n"
         "[[point]]\nname = \"frequency\"\ntable = \"holding\"\naddress = 1\ntype = \"u16\"\n"
         "min = 0\naccess = \"operate\"\n" +
         code +
         "[[point]]\nname = \"limit\"\ntable = \"holding\"\naddress = 4\ntype = \"u32\"\n"
         "access = \"operate\"\n" +
         code2 + extra +
         "[[point]]\nname = \"speed\"\ntable = \"input\"\naddress = 16\ntype = \"u16\"\n"
         "[[point]]\nname = \"status\"\ntable = \"input\"\naddress = 17\ntype = \"u16\"\n"
         "[common]\nspeed_rpm = \"speed\"\nsetpoint_rpm = \"frequency\"\n"
         "running = { point = \"status\", bit = 0 }\n"
         "stop = { point = \"control\", value = 0 }\n"
         "run_forward = { point = \"control\", value = 1 }\n";
}

const std::string kUnsaved = "write_code = 0x41\n";

// The RTU frame to unit 1: the PDU and its CRC, low byte first (Serial Line 6.2.2).
Bytes unit1_rtu(Bytes pdu) {
  pdu.insert(pdu.begin(), 0x01);
  append_crc16_modbus(pdu);
  return pdu;
}

// A frame as an [[example]] prints it: hex bytes, space-separated.
std::string example_hex(const Bytes& frame) {
  std::string out;
  for (const std::uint8_t b : frame) {
    static constexpr char kDigits[] = "0123456789ABCDEF";
    if (!out.empty()) out += ' ';
    out += kDigits[b >> 4];
    out += kDigits[b & 0x0F];
  }
  return out;
}

TEST(ModbusWriteCode, APointsWritesGoWithItsCodeAndOnlyItsAndTheEchoConfirmsThem) {
  const support::ProfileFile file(unsaved_inverter(kUnsaved), "inv.toml");
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};
  ASSERT_TRUE(b.until_online());
  TimePoint from = b.rig.now();
  ASSERT_EQ(b.write({1200}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  // The setpoint with 0x41, the command word (no write_code) with FC 06.
  EXPECT_EQ(b.count(unit1_rtu({0x41, 0x00, 0x01, 0x04, 0xB0}), from), 1u);
  EXPECT_EQ(b.count(unit1_rtu({0x06, 0x00, 0x00, 0x00, 0x01}), from), 1u);
  EXPECT_TRUE(b.rig.run_until([&] { return b.read("speed_rpm") == 1200u; }, 2s));
  EXPECT_EQ(b.read("setpoint_rpm"), 1200u);
  // A point without the code keeps the protocol's: the limit with FC 16.
  from = b.rig.now();
  ASSERT_EQ(b.write_point("limit", 70000), Outcome::ok);
  EXPECT_EQ(b.count(unit1_rtu({0x10, 0x00, 0x04, 0x00, 0x02, 0x04, 0x00, 0x01, 0x11, 0x70}), from),
            1u);
  EXPECT_EQ(b.read("limit"), 70000u);
  // The frequency never went with the saving code.
  for (const Bytes& f : b.frames()) {
    ASSERT_GE(f.size(), 4u);
    EXPECT_FALSE(f[1] == 0x06 && f[2] == 0x00 && f[3] == 0x01) << "a saving write went out";
  }
}

// The manuals describe 0x41 with 0x06's frame and print no 0x41 reply: a drive that answers under
// 0x06 has taken the write, and the PLC is told so.
TEST(ModbusWriteCode, AnEchoUnderTheCodeOfItsLayoutConfirmsTheWrite) {
  const support::ProfileFile file(unsaved_inverter(kUnsaved), "inv.toml");
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.control("reply-code layout").rfind("ok", 0), 0u);
  const TimePoint from = b.rig.now();
  ASSERT_EQ(b.write({900}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(b.count(unit1_rtu({0x41, 0x00, 0x01, 0x03, 0x84}), from), 1u);
  EXPECT_EQ(b.read("setpoint_rpm"), 900u);
}

// The simulator plays a drive that knows the code for the points that name it only: any other
// register written with it is an illegal function (01), as a drive whose manual gives the code
// for some registers would answer for the others.
TEST(ModbusWriteCode, TheSimulatorServesTheCodeOnItsPointsOnly) {
  auto parsed = parse_profile(unsaved_inverter(kUnsaved), "inv.toml");
  ASSERT_TRUE(std::holds_alternative<Profile>(parsed));
  ModbusSimulator sim(1, std::get<Profile>(std::move(parsed)));
  const TimePoint t{};
  const Bytes own = sim.on_receive(unit1_rtu({0x41, 0x00, 0x01, 0x05, 0xDC}), t);
  EXPECT_EQ(own, unit1_rtu({0x41, 0x00, 0x01, 0x05, 0xDC}));
  const Bytes other = sim.on_receive(unit1_rtu({0x41, 0x00, 0x00, 0x00, 0x01}), t + 1s);
  EXPECT_EQ(other, unit1_rtu({0xC1, 0x01}));
}

// An exception under either code (0xC1, or 0x86 from a drive that answers as 0x06) is the drive's
// refusal: exception 04 to the PLC, and the setpoint in force stays.
TEST(ModbusWriteCode, AnExceptionUnderEitherCodeIsARefusal) {
  const support::ProfileFile file(unsaved_inverter(kUnsaved), "inv.toml");
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.write({900}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(b.control("refuse holding 1 4 1").rfind("ok", 0), 0u);
  EXPECT_EQ(b.write({1500}, kSetpointRegister), Outcome::refused);
  EXPECT_EQ(b.read("setpoint_rpm"), 900u);
  ASSERT_EQ(b.control("reply-code layout").rfind("ok", 0), 0u);
  ASSERT_EQ(b.control("refuse holding 1 4 1").rfind("ok", 0), 0u);
  EXPECT_EQ(b.write({1600}, kSetpointRegister), Outcome::refused);
  EXPECT_EQ(b.read("setpoint_rpm"), 900u);
  ASSERT_EQ(b.write({1700}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(b.read("setpoint_rpm"), 1700u);
}

// The flaw of a reply found by its CRC alone: for some values the echo's first bytes end in a good
// CRC, and the write the drive took was answered as refused. Delimited by its layout, it is whole.
TEST(ModbusWriteCode, AnEchoHoldingAGoodCrcBeforeItsEndIsTakenWhole) {
  std::optional<std::uint16_t> value;
  for (std::uint32_t v = 0; v <= 0xFFFF && !value; ++v) {
    const Bytes echo = unit1_rtu(
        {0x41, 0x00, 0x01, static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v & 0xFF)});
    if (crc_end(echo) != echo.size()) value = static_cast<std::uint16_t>(v);
  }
  ASSERT_TRUE(value) << "some value's echo must hold an early CRC for this test to mean anything";
  const support::ProfileFile file(unsaved_inverter(kUnsaved), "inv.toml");
  test::AdapterBench b{drivegate_adapter, {.options = {{"profile", file.path}}}};
  ASSERT_TRUE(b.until_online());
  const TimePoint from = b.rig.now();
  ASSERT_EQ(b.write({*value}, kSetpointRegister), Outcome::ok);
  EXPECT_EQ(b.count(unit1_rtu({0x41, 0x00, 0x01, static_cast<std::uint8_t>(*value >> 8),
                               static_cast<std::uint8_t>(*value & 0xFF)}),
                    from),
            1u);
  EXPECT_EQ(b.read("setpoint_rpm"), *value);
}

std::vector<std::string> code_errors_of(const std::string& text) {
  auto parsed = parse_profile(text, "p.toml");
  if (std::holds_alternative<Profile>(parsed)) return {};
  return std::get<std::vector<std::string>>(parsed);
}

TEST(ModbusWriteCode, ACodeIsAUserDefinedOneOnAWritableRegisterWrittenWithFc06) {
  EXPECT_TRUE(code_errors_of(unsaved_inverter(kUnsaved)).empty());
  EXPECT_TRUE(code_errors_of(unsaved_inverter("write_code = 100\n")).empty());
  EXPECT_TRUE(code_errors_of(unsaved_inverter("write_code = 110\n")).empty());
  // The protocol's own codes, a public one and an exception code are not a device's own.
  for (const char* code : {"write_code = 6\n", "write_code = 0x10\n", "write_code = 0x07\n",
                           "write_code = 0xC1\n", "write_code = 73\n"}) {
    EXPECT_THAT(code_errors_of(unsaved_inverter(code)),
                ElementsAre(HasSubstr("p.toml:19: point.write_code: must be a user-defined "
                                      "function code (65..72 or 100..110")))
        << code;
  }
  // A read-only point, and an input register, are not written at all.
  for (const char* table : {"holding\"\naccess = \"read", "input"}) {
    const std::string other = "[[point]]\nname = \"other\"\ntable = \"" + std::string(table) +
                              "\"\naddress = 30\ntype = \"u16\"\nwrite_code = 0x41\n";
    EXPECT_THAT(code_errors_of(unsaved_inverter("", "", other)),
                ElementsAre(HasSubstr("point.write_code: names how a point is written")))
        << table;
  }
  // Laid out as FC 06: not on a point written with FC 16 (two registers, or write = "multiple").
  EXPECT_THAT(code_errors_of(unsaved_inverter("", kUnsaved)),
              ElementsAre(HasSubstr("p.toml:25: point.write_code: is laid out as FC 06")));
  EXPECT_THAT(code_errors_of(support::replaced(unsaved_inverter(kUnsaved), "max_gap = 0\n",
                                               "max_gap = 0\nwrite = \"multiple\"\n")),
              ElementsAre(HasSubstr("point.write_code: is laid out as FC 06")));
  const Profile p = std::get<Profile>(parse_profile(unsaved_inverter(kUnsaved), "p.toml"));
  const std::vector<CodeLayout> layouts = write_layouts(p);
  ASSERT_EQ(layouts.size(), 1u);
  EXPECT_EQ(layouts[0].code, 0x41);
  EXPECT_EQ(layouts[0].like, fc::write_single_register);
}

// The manual's own frames may use the code: its request writes the point, its echo may be under
// either code.
TEST(ModbusWriteCode, AnExampleFrameMayUseThePointsCode) {
  const std::string examples =
      "[[example]]\nrequest = \"" + example_hex(unit1_rtu({0x41, 0x00, 0x01, 0x05, 0xDC})) +
      "\"\nreply = \"" + example_hex(unit1_rtu({0x41, 0x00, 0x01, 0x05, 0xDC})) +
      "\"\nexpect = { frequency = 1500 }\n"
      "[[example]]\nrequest = \"" +
      example_hex(unit1_rtu({0x41, 0x00, 0x01, 0x05, 0xDC})) + "\"\nreply = \"" +
      example_hex(unit1_rtu({0x06, 0x00, 0x01, 0x05, 0xDC})) +
      "\"\nexpect = { frequency = 1500 }\n";
  const auto parsed = parse_profile(unsaved_inverter(kUnsaved) + examples, "p.toml");
  ASSERT_TRUE(std::holds_alternative<Profile>(parsed));
  EXPECT_THAT(check_examples(std::get<Profile>(parsed), "p.toml"), testing::IsEmpty());
  // A reply under a third code is not the echo.
  const std::string wrong =
      "[[example]]\nrequest = \"" + example_hex(unit1_rtu({0x41, 0x00, 0x01, 0x05, 0xDC})) +
      "\"\nreply = \"" + example_hex(unit1_rtu({0x42, 0x00, 0x01, 0x05, 0xDC})) +
      "\"\nexpect = { frequency = 1500 }\n";
  const auto bad = parse_profile(unsaved_inverter(kUnsaved) + wrong, "p.toml");
  ASSERT_TRUE(std::holds_alternative<Profile>(bad));
  EXPECT_THAT(check_examples(std::get<Profile>(bad), "p.toml"),
              ElementsAre(HasSubstr("the reply is not the slave's echo of the request")));
  // The code writes the points that name it: not the command word.
  const std::string elsewhere = "[[example]]\nrequest = \"" +
                                example_hex(unit1_rtu({0x41, 0x00, 0x00, 0x00, 0x01})) +
                                "\"\nexpect = { control = 1 }\n";
  const auto other = parse_profile(unsaved_inverter(kUnsaved) + elsewhere, "p.toml");
  ASSERT_TRUE(std::holds_alternative<Profile>(other));
  EXPECT_THAT(check_examples(std::get<Profile>(other), "p.toml"),
              ElementsAre(HasSubstr("'control' is not written with 0x41")));
}

}  // namespace
}  // namespace drivegate::modbus_device
