// Profiles: the shipped example read whole, and every way a profile can be wrong refused with the
// line it is on.
#include "profile.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "example_profile.h"
#include "profile_support.h"

namespace drivegate::modbus_device {
namespace {

using support::errors_of;
using support::expect_refused;
using support::parsed;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

// The least valid profile, to which each test adds what it is about.
const std::string kHead =
    "[profile]\nname = \"t\"\nsource = \"a manual\"\n"  // lines 1-3
    "[[point]]\nname = \"status\"\ntable = \"holding\"\naddress = 10\ntype = \"u16\"\n";  // 4-8

TEST(Profile, TheExampleOfTheIssueReadsAsWritten) {
  const Profile p = parsed(shipped::text("example-vfd"));
  EXPECT_EQ(p.name, "example-vfd");
  EXPECT_EQ(p.line.baud, 19200u);
  EXPECT_EQ(p.line.parity, Parity::even);
  EXPECT_EQ(p.line.framing, Framing::rtu);
  EXPECT_EQ(p.modbus.max_registers, 32);
  EXPECT_EQ(p.modbus.max_gap, 4);
  EXPECT_EQ(p.modbus.write, WriteFunction::single);
  EXPECT_EQ(p.modbus.timeout_ms, 100u);
  ASSERT_EQ(p.points.size(), 6u);
  const ProfilePoint& current = p.points[*p.find("motor_current")];
  EXPECT_EQ(current.table, Table::input);
  EXPECT_EQ(current.address, 202);
  EXPECT_EQ(current.type, ValueType::f32);
  EXPECT_EQ(current.byte_order, ByteOrder::cdab);  // word_order = "little"
  EXPECT_EQ(current.unit, "A");
  EXPECT_EQ(p.points[*p.find("speed_actual")].scale, 0.1);
  const ProfilePoint& reference = p.points[*p.find("speed_reference")];
  EXPECT_EQ(reference.access, PointAccess::operate);
  EXPECT_EQ(reference.min, 0.0);
  EXPECT_EQ(reference.max, 3000.0);
  EXPECT_EQ(p.points[*p.find("control_word")].access, PointAccess::maintain);
  EXPECT_EQ(p.points[*p.find("status_word")].access, PointAccess::maintain);  // holding: default
  EXPECT_EQ(p.points[*p.find("fault_number")].access, PointAccess::read);

  const CommonBindings& c = p.common;
  EXPECT_EQ(c.speed_rpm, p.find("speed_actual"));
  EXPECT_EQ(c.setpoint_rpm, p.find("speed_reference"));
  ASSERT_TRUE(c.running && c.fault && c.fault_code && c.stop && c.run_forward && c.run_reverse &&
              c.reset_fault);
  EXPECT_EQ(c.running->point, *p.find("status_word"));
  EXPECT_THAT(c.running->bits, ElementsAre(2));
  EXPECT_THAT(c.fault->bits, ElementsAre(3));
  EXPECT_EQ(c.fault_code->point, *p.find("fault_number"));
  EXPECT_EQ(c.fault_code->map,
            (std::map<std::uint32_t, Fault>{{0, Fault::none},
                                            {2, Fault::over_current},
                                            {3, Fault::over_voltage},
                                            {5, Fault::drive_over_temperature}}));
  EXPECT_EQ(c.fault_code->other, Fault::other);
  EXPECT_EQ(c.stop->value, 0x0006);
  EXPECT_EQ(c.run_forward->value, 0x000F);
  EXPECT_EQ(c.run_reverse->value, 0x080F);
  EXPECT_EQ(c.reset_fault->value, 0x0080);
  EXPECT_EQ(c.stop->point, *p.find("control_word"));
}

TEST(Profile, DefaultsAreTheSerialLineSpecificationsOwn) {
  const Profile p = parsed(kHead);
  EXPECT_EQ(p.line.baud, 19200u);          // Serial Line 2.5.1
  EXPECT_EQ(p.line.parity, Parity::even);  // Serial Line 2.5.1
  EXPECT_EQ(p.line.framing, Framing::rtu);
  EXPECT_EQ(p.modbus.max_registers, 125);  // Application Protocol 6.3
  EXPECT_EQ(p.modbus.max_gap, 0);
}

TEST(Profile, SyntaxErrorsNameTheLine) {
  EXPECT_THAT(errors_of(kHead + "[common\n"), ElementsAre(HasSubstr("p.toml:9: ")));
}

TEST(Profile, WhatIsMissingOrUnknownIsNamed) {
  expect_refused(errors_of,
                 {{"[profile]\nname = \"t\"\n",
                   {"p.toml: point: a profile needs at least one [[point]]",
                    "p.toml:1: profile.source: required key is missing"}},
                  {kHead + "colour = \"red\"\n", {"p.toml:9: point.colour: unknown key"}},
                  {kHead + "[line]\nparity = \"mark\"\n",
                   {"p.toml:10: line.parity: must be one of none, even, odd (got 'mark')"}},
                  {kHead + "[modbus]\nmax_registers = 126\n",
                   {"p.toml:10: modbus.max_registers: must be in 1..125"}}});
}

TEST(Profile, PointsAreCheckedOneByOne) {
  const auto point = [](const std::string& body) {
    return errors_of(kHead + "[[point]]\n" + body);  // the point starts on line 9
  };
  expect_refused(point,
                 {{"name = \"Speed\"\ntable = \"input\"\naddress = 1\ntype = \"u16\"\n",
                   {"p.toml:10: point.name: must be snake_case"}},
                  {"name = \"status\"\ntable = \"input\"\naddress = 1\ntype = \"u16\"\n",
                   {"p.toml:10: point.name: 'status' is defined twice (first on line 4)"}},
                  {"name = \"run\"\ntable = \"coil\"\naddress = 1\ntype = \"u16\"\n",
                   {"p.toml:13: point.type: a coil or discrete input is of type bit"}},
                  {"name = \"a\"\ntable = \"input\"\naddress = 1\ntype = \"bit\"\n",
                   {"point.type: type bit is for coils and discrete inputs"}},
                  {"name = \"a\"\ntable = \"input\"\naddress = 65535\ntype = \"u32\"\n",
                   {"point.address: a point of 2 registers at 65535 runs past"}},
                  {"name = \"a\"\ntable = \"input\"\naddress = 1\ntype = \"u16\"\n"
                   "word_order = \"little\"\n",
                   {"p.toml:14: point.word_order: applies to the 32- and 64-bit types"}},
                  {"name = \"a\"\ntable = \"input\"\naddress = 1\ntype = \"u16\"\n"
                   "access = \"operate\"\n",
                   {"point.access: an input register or discrete input cannot be written"}},
                  {"name = \"a\"\ntable = \"input\"\naddress = 1\ntype = \"u16\"\nmax = 5\n",
                   {"point.max: limits a write"}},
                  {"name = \"a\"\ntable = \"holding\"\naddress = 1\ntype = \"u16\"\nmin = 5\n"
                   "max = 4\n",
                   {"point.min: is above point.max"}},
                  {"name = \"a\"\ntable = \"holding\"\naddress = 1\ntype = \"u16\"\n"
                   "scale = 0\n",
                   {"point.scale: must not be 0"}}});
}

TEST(Profile, OverlappingPointsNameBoth) {
  // status is holding 10; a u32 at 9 takes 9 and 10.
  EXPECT_THAT(errors_of(kHead + "[[point]]\nname = \"wide\"\ntable = \"holding\"\naddress = 9\n"
                                "type = \"u32\"\n"),
              ElementsAre(HasSubstr("p.toml:9: point: 'wide' overlaps 'status' (line 4) in the "
                                    "holding table")));
  // The same address in another table is another register.
  parsed(kHead + "[[point]]\nname = \"other\"\ntable = \"input\"\naddress = 10\ntype = \"u16\"\n");
}

TEST(Profile, APointLargerThanTheDevicesReadIsRefused) {
  EXPECT_THAT(errors_of("[profile]\nname = \"t\"\nsource = \"m\"\n[modbus]\nmax_registers = 1\n"
                        "[[point]]\nname = \"a\"\ntable = \"input\"\naddress = 1\n"
                        "type = \"f32\"\n"),
              ElementsAre(HasSubstr("point.type: takes 2 registers, more than the device reads "
                                    "at once ([modbus] max_registers = 1)")));
}

TEST(Profile, CommonBindingsMustNameRealPointsAndBits) {
  const auto common = [](const std::string& body) {
    return errors_of(kHead + "[common]\n" + body);
  };
  expect_refused(
      common,
      {{"speed_rpm = \"speed\"\n", {"p.toml:10: common.speed_rpm: no point is called 'speed'"}},
       {"running = { point = \"status\", bit = 16 }\n",
        {"common.running.bit: must be in 0..15 (got 16)"}},
       {"running = { point = \"status\" }\n", {"common.running.bit: required key is missing"}}});
  EXPECT_THAT(
      errors_of(kHead + "[[point]]\nname = \"word\"\ntable = \"input\"\naddress = 1\n"
                        "type = \"u32\"\n[common]\nfault = { point = \"word\", bit = 1 }\n"),
      ElementsAre(HasSubstr("common.fault.point: 'word' must be a one-register point")));
  expect_refused(common, {{"running = \"status\"\n", {"common.running: must be an inline table"}},
                          {"fault_code = { point = \"status\", map = { 1 = \"overcurrent\" } }\n",
                           {"unknown fault label 'overcurrent' (known: none, "}},
                          {"fault_code = { point = \"status\", map = { 1 = \"comm_lost\" } }\n",
                           {"comm_lost is the gateway's own fault"}},
                          {"fault_code = { point = \"status\", map = { one = \"other\" } }\n",
                           {"key 'one' must be a native fault value"}},
                          {"stop = { point = \"status\", value = 70000 }\n",
                           {"common.stop.value: must be in 0..65535"}},
                          {"run_forward = { point = \"status\", value = 1 }\n",
                           {"run_forward or run_reverse without stop"}}});
  // A command is written: the point must be a holding register.
  EXPECT_THAT(
      errors_of(kHead + "[[point]]\nname = \"state\"\ntable = \"input\"\naddress = 1\n"
                        "type = \"u16\"\n[common]\nstop = { point = \"state\", value = 0 }\n"),
      ElementsAre(HasSubstr("common.stop.point: 'state' must be a one-register holding "
                            "point")));
  // Hex keys in the fault map are native values too.
  const Profile p = parsed(kHead +
                           "[common]\nfault_code = { point = \"status\", map = "
                           "{ \"0x11\" = \"over_current\" } }\n");
  ASSERT_TRUE(p.common.fault_code);
  EXPECT_EQ(p.common.fault_code->map.at(0x11), Fault::over_current);
}

// The common block is the drive's state as of one data age: a point bound to it cannot have a
// poll interval of its own (a status word read hourly would show a running drive stopped).
TEST(Profile, APointBoundToTheCommonBlockHasNoPollIntervalOfItsOwn) {
  const std::string slow = kHead + "poll_ms = 3600000\n";  // the status word, line 9
  expect_refused(
      errors_of,
      {{slow + "[common]\nrunning = { point = \"status\", bit = 2 }\n"
               "fault = { point = \"status\", bit = 3 }\n",
        {"p.toml:4: point.poll_ms: 'status' is bound to the common block (common.running), which "
         "is polled at the device's poll_ms: remove poll_ms"}},
       {slow + "[common]\nstop = { point = \"status\", value = 6 }\n", {"(common.stop)"}}});
  // A point of the device's own keeps its interval.
  const Profile p = parsed(slow);
  EXPECT_EQ(p.points[0].poll_ms, 3600000u);
}

TEST(Profile, EveryErrorIsReportedInOnePass) {
  const auto errors = errors_of(
      "[profile]\nname = \"t\"\nsource = \"m\"\n"
      "[[point]]\nname = \"a\"\ntable = \"input\"\naddress = -1\ntype = \"u16\"\n"
      "[[point]]\nname = \"b\"\ntable = \"attic\"\naddress = 1\ntype = \"u16\"\n");
  EXPECT_THAT(errors, ElementsAre(HasSubstr("p.toml:7: point.address: must be in 0..65535"),
                                  HasSubstr("p.toml:11: point.table: must be one of")));
}

}  // namespace
}  // namespace drivegate::modbus_device
