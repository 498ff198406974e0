// The bindings real drives need (docs/profiles.md, "Masks, several bits, bit fields, coils"):
// masked points sharing a register, running and fault as any of several bits, a fault code over
// a bit field, commands to coils and a two-register setpoint. Each is read from a profile (and
// every wrong form refused with its line), played by hand against the driver (the frames on the
// wire), served by the simulator, and run on the bus engine as a PLC reads the common block.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "common_block.h"
#include "driver.h"
#include "profile.h"
#include "profile_support.h"
#include "simulator.h"

namespace drivegate::modbus_device::modbus_bindings_test {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;
using namespace support;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr std::uint8_t kSlave = 7;

// A drive of invented addresses with every binding of this kind. Holding 10 is the status word:
// the state in its low byte (running forward bit 0, reverse bit 1, tripped bit 3), the fault
// number in its high byte; holding 11 a warning number (high byte) and a mode (low nibble);
// input 20 a trip bit field; coils 0 and 1 run and reset; holding 0..1 the reference in 0.01 rpm.
const std::string kDrive =
    "[profile]\nname = \"bind\"\nsource = \"a test\"\n"                                 // 1-3
    "[[point]]\nname = \"state\"\ntable = \"holding\"\naddress = 10\ntype = \"u16\"\n"  // 4-8
    "mask = 0x00FF\n"                                                                   // 9
    "[[point]]\nname = \"fault_number\"\ntable = \"holding\"\naddress = 10\ntype = \"u16\"\n"
    "mask = 0xFF00\n"  // 15
    "[[point]]\nname = \"warning\"\ntable = \"holding\"\naddress = 11\ntype = \"u16\"\n"
    "mask = 0xFF00\n"
    "[[point]]\nname = \"mode\"\ntable = \"holding\"\naddress = 11\ntype = \"u16\"\n"
    "mask = 0x000F\n"
    "[[point]]\nname = \"trips\"\ntable = \"input\"\naddress = 20\ntype = \"u16\"\n"
    "[[point]]\nname = \"run_coil\"\ntable = \"coil\"\naddress = 0\ntype = \"bit\"\n"
    "[[point]]\nname = \"reset_coil\"\ntable = \"coil\"\naddress = 1\ntype = \"bit\"\n"
    "[[point]]\nname = \"reference\"\ntable = \"holding\"\naddress = 0\ntype = \"u32\"\n"
    "scale = 0.01\n"
    "[[point]]\nname = \"speed\"\ntable = \"input\"\naddress = 30\ntype = \"s16\"\n"
    "[common]\n"
    "speed_rpm = \"speed\"\n"
    "setpoint_rpm = \"reference\"\n"
    "running = { point = \"state\", any_bit = [0, 1] }\n"
    "fault = { point = \"state\", bit = 3 }\n"
    "fault_code = { point = \"fault_number\", map = { 0 = \"none\", 2 = \"over_current\" } }\n"
    "stop = { point = \"run_coil\", value = 0 }\n"
    "run_forward = { point = \"run_coil\", value = 1 }\n"
    "reset_fault = { point = \"reset_coil\", value = 1 }\n";

// The drive with its fault code read from the trip bit field instead (and no fault bit: the
// code says whether a trip is active).
const std::string kTripBits =
    "fault_code = { point = \"trips\", bits = { 0 = \"over_current\", 1 = \"over_voltage\", "
    "4 = \"under_voltage\" }, other = \"hardware_fault\" }\n";

std::string with_trip_bits() {
  std::string t = replaced(kDrive, "fault = { point = \"state\", bit = 3 }\n", "");
  return replaced(t,
                  "fault_code = { point = \"fault_number\", map = { 0 = \"none\", 2 = "
                  "\"over_current\" } }\n",
                  kTripBits);
}

// The least valid profile, to which each test adds its points (support::point).
const std::string kHead = "[profile]\nname = \"t\"\nsource = \"a manual\"\n";  // lines 1-3

// ---- The profile

TEST(Bindings, TheDriveReadsAsWritten) {
  const Profile p = parsed(kDrive);
  const ProfilePoint& state = p.points[*p.find("state")];
  EXPECT_EQ(state.mask, 0x00FF);
  EXPECT_EQ(state.access, PointAccess::read);  // a masked holding point is read-only
  EXPECT_EQ(p.points[*p.find("fault_number")].mask, 0xFF00);
  EXPECT_FALSE(p.points[*p.find("trips")].mask);
  const CommonBindings& c = p.common;
  ASSERT_TRUE(c.running && c.fault && c.fault_code && c.stop && c.run_forward && c.reset_fault);
  EXPECT_THAT(c.running->bits, ElementsAre(0, 1));
  EXPECT_EQ(c.running->mask(), 0x0003);
  EXPECT_THAT(c.fault->bits, ElementsAre(3));
  EXPECT_EQ(c.stop->point, *p.find("run_coil"));
  EXPECT_EQ(c.stop->value, 0);
  EXPECT_EQ(c.run_forward->value, 1);
  EXPECT_EQ(c.setpoint_rpm, p.find("reference"));
  const Profile b = parsed(with_trip_bits());
  ASSERT_TRUE(b.common.fault_code);
  EXPECT_EQ(b.common.fault_code->bits,
            (std::map<std::uint8_t, Fault>{
                {0, Fault::over_current}, {1, Fault::over_voltage}, {4, Fault::under_voltage}}));
  EXPECT_TRUE(b.common.fault_code->map.empty());
  EXPECT_EQ(b.common.fault_code->other, Fault::hardware_fault);
}

TEST(Bindings, MasksThatOverlapAreRefusedWithTheLaterLine) {
  // Lines 4-9 and 10-15.
  expect_refused(
      errors_of,
      {{kHead + point("a", "holding", 5, "u16", "mask = 0x0FF0\n") +
            point("b", "holding", 5, "u16", "mask = 0x0F00\n"),
        {"p.toml:10: point: 'b' overlaps 'a' (line 4) in the holding table: their masks share bits "
         "(0x0F00)"}},
       // A masked point and a whole register may not share it.
       {kHead + point("a", "holding", 5, "u16", "mask = 0x00FF\n") +
            point("b", "holding", 5, "u16"),
        {"p.toml:10: point: 'b' overlaps 'a' (line 4) in the holding table: a register is shared "
         "only by points whose masks do not overlap"}},
       // Nor a two-register point over the masked one's register.
       {kHead + point("a", "input", 6, "u16", "mask = 0x00FF\n") + point("b", "input", 5, "u32"),
        {"p.toml:10: point: 'b' overlaps 'a' (line 4)"}},
       // Three on one register: the first and the last overlap, the middle one overlaps neither.
       {kHead + point("a", "holding", 5, "u16", "mask = 0xFF00\n") +
            point("b", "holding", 5, "u16", "mask = 0x000F\n") +
            point("c", "holding", 5, "u16", "mask = 0x0100\n"),
        {"p.toml:16: point: 'c' overlaps 'a' (line 4) in the holding table: their masks share bits "
         "(0x0100)"}}});
  // Disjoint masks share the register; another table's register 5 is another register.
  const Profile p =
      parsed(kHead + point("a", "holding", 5, "u16", "mask = 0xFF00\n") +
             point("b", "holding", 5, "u16", "mask = 0x00F0\n") +
             point("c", "holding", 5, "u16", "mask = 0x000F\n") + point("d", "input", 5, "u16"));
  EXPECT_EQ(p.points.size(), 4u);
}

TEST(Bindings, AMaskIsSomeBitsOfAU16ThatIsReadOnly) {
  // The profile of one point `a` of `type` with `more` in it.
  const auto masked = [](const std::string& type, const std::string& more,
                         const std::string& table = "holding") {
    return kHead + point("a", table, 5, type, more);
  };
  expect_refused(
      errors_of,
      {{masked("u16", "mask = 0\n"),
        {"p.toml:9: point.mask: must not be 0: a mask of no bits reads nothing"}},
       {masked("u16", "mask = 0x10000\n"), {"point.mask: must be in 0..65535"}},
       {masked("u16", "mask = -1\n"), {"point.mask: must be in 0..65535"}},
       {masked("u16", "mask = \"0xFF00\"\n"), {"point.mask: must be an integer"}},
       {masked("s16", "mask = 0xFF00\n"), {"point.mask: applies to u16 register points only"}},
       {masked("u32", "mask = 0xFF00\n"), {"point.mask: applies to u16 register points only"}},
       {masked("bit", "mask = 1\n", "coil"), {"point.mask: applies to u16 register points only"}},
       // Read-modify-write is not done: a masked point is never written.
       {masked("u16", "mask = 0xFF00\naccess = \"operate\"\n"),
        {"p.toml:10: point.access: a masked point is read-only"}},
       {masked("u16", "mask = 0xFF00\naccess = \"maintain\"\n"),
        {"point.access: a masked point is read-only"}},
       {masked("u16", "mask = 0xFF00\nmax = 3\n"),
        {"point.max: limits a write: a masked point is read-only"}}});
  EXPECT_EQ(parsed(masked("u16", "mask = 0xFF00\naccess = \"read\"\n")).points.at(0).access,
            PointAccess::read);
  // Nor written by a binding.
  expect_refused(errors_of, {{masked("u16", "mask = 0x00FF\n") +
                                  "[common]\nstop = { point = \"a\", value = 0 }\n",
                              {"p.toml:11: common.stop.point: 'a' is masked, so read-only"}},
                             {masked("u16", "mask = 0x00FF\n") + "[common]\nsetpoint_rpm = \"a\"\n",
                              {"common.setpoint_rpm: 'a' is masked, so read-only"}}});
}

// The errors of `head` whose [common] block binds `key` as a case says.
auto bound(const std::string& head, const std::string& key) {
  return [=](const std::string& binding) {
    return errors_of(head + "[common]\n" + key + " = " + binding + "\n");
  };
}

TEST(Bindings, AnyBitIsOneToSixteenBitsOfTheRegister) {
  const std::string head = kHead + point("s", "holding", 5, "u16");  // lines 4-8
  expect_refused(
      bound(head, "running"),
      {{"{ point = \"s\", any_bit = [0, 16] }",
        {"p.toml:10: common.running.any_bit: bits are numbers 0..15 of a register"}},
       {"{ point = \"s\", any_bit = [-1] }", {"common.running.any_bit: bits are numbers 0..15"}},
       {"{ point = \"s\", any_bit = [1.0] }", {"common.running.any_bit: bits are numbers 0..15"}},
       {"{ point = \"s\", any_bit = [] }",
        {"common.running.any_bit: must be a list of 1..16 bit numbers"}},
       {"{ point = \"s\", any_bit = 1 }",
        {"common.running.any_bit: must be a list of 1..16 bit numbers"}},
       {"{ point = \"s\", any_bit = [2, 2] }", {"common.running.any_bit: bit 2 is listed twice"}},
       {"{ point = \"s\", bit = 1, any_bit = [0, 1] }",
        {"common.running.any_bit: bit or any_bit, not both"}},
       {"{ point = \"s\", any_bit = [0, 1], spare = 1 }", {"common.running.spare: unknown key"}}});
  // A bit point has only its own bit.
  EXPECT_THAT(errors_of(head + point("b", "discrete", 1, "bit") +
                        "[common]\nfault = { point = \"b\", any_bit = [0] }\n"),
              ElementsAre(HasSubstr("common.fault.any_bit: a bit point has no bits but its own")));
  // A masked point's bits are its value's: 0..7 of a high byte, not the register's 8..15.
  const std::string high = kHead + point("h", "holding", 5, "u16", "mask = 0xFF00\n");
  expect_refused(errors_of, {{high + "[common]\nfault = { point = \"h\", any_bit = [0, 8] }\n",
                              {"common.fault.any_bit: bit 8 is not a bit of 'h' (its mask 0xFF00 "
                               "gives it the bits of 0x00FF)"}},
                             {high + "[common]\nfault = { point = \"h\", bit = 9 }\n",
                              {"common.fault.bit: bit 9 is not a bit of 'h'"}}});
  EXPECT_THAT(
      parsed(high + "[common]\nfault = { point = \"h\", any_bit = [7, 0] }\n").common.fault->bits,
      ElementsAre(7, 0));
}

TEST(Bindings, AFaultBitFieldNamesBitsOfAnIntegerPoint) {
  const std::string head = kHead + point("t", "input", 5, "u16") +             // 4-8
                           point("f", "input", 6, "f32") +                     // 9-13
                           point("w", "input", 8, "u32") +                     // 14-18
                           point("h", "input", 10, "u16", "mask = 0xF000\n");  // 19-24
  const auto code = bound(head, "fault_code");
  expect_refused(
      code,
      {{"{ point = \"t\", bits = { 16 = \"over_current\" } }",
        {"p.toml:26: common.fault_code.bits: key '16' must be a bit number 0..15 of 't'"}},
       {"{ point = \"t\", bits = { x = \"over_current\" } }",
        {"key 'x' must be a bit number 0..15 of 't'"}},
       {"{ point = \"t\", bits = { 0 = \"none\" } }",
        {"common.fault_code.bits.0: a bit set is a trip: none is what no bit set means"}},
       {"{ point = \"t\", bits = { 0 = \"overcurrent\" } }", {"unknown fault label 'overcurrent'"}},
       {"{ point = \"t\", bits = { 0 = \"comm_lost\" } }",
        {"comm_lost is the gateway's own fault"}},
       {"{ point = \"t\", bits = {} }", {"common.fault_code.bits: must name at least one bit"}},
       {"{ point = \"t\", bits = [0, 1] }",
        {"common.fault_code.bits: must be a table of a bit number"}},
       {"{ point = \"t\", map = { 1 = \"other\" }, bits = { 0 = \"other\" } }",
        {"common.fault_code.bits: map (the point's values) or bits (its bits), not both"}},
       {"{ point = \"f\", bits = { 0 = \"other\" } }",
        {"common.fault_code.point: 'f' is of type f32: a bit field is a point of type u16, s16, "
         "u32 or s32"}},
       {"{ point = \"h\", bits = { 4 = \"other\" } }",
        {"bit 4 is not a bit of 'h' (its mask 0xF000 gives it the bits of 0x000F)"}}});
  // A two-register bit field has 32 bits.
  EXPECT_EQ(parsed(head + "[common]\nfault_code = { point = \"w\", bits = { 31 = \"other\" } }\n")
                .common.fault_code->bits.at(31),
            Fault::other);
  EXPECT_THAT(code("{ point = \"w\", bits = { 32 = \"other\" } }"),
              ElementsAre(HasSubstr("key '32' must be a bit number 0..31 of 'w'")));
}

TEST(Bindings, ACommandToACoilIsZeroOrOne) {
  const std::string head = kHead + point("run", "coil", 0, "bit") +  // 4-8
                           point("di", "discrete", 0, "bit");        // 9-13
  const auto common = [&](const std::string& body) {
    return errors_of(head + "[common]\n" + body);
  };
  expect_refused(common,
                 {{"stop = { point = \"run\", value = 2 }\n",
                   {"p.toml:15: common.stop.value: 'run' is a coil: it is written 0 or 1 (got 2)"}},
                  {"stop = { point = \"run\", value = 0xFF00 }\n",
                   {"'run' is a coil: it is written 0 or 1 (got 65280)"}},
                  {"stop = { point = \"di\", value = 0 }\n",
                   {"common.stop.point: 'di' must be a one-register holding point or a coil"}}});
  const Profile p = parsed(head +
                           "[common]\nstop = { point = \"run\", value = 0 }\n"
                           "run_forward = { point = \"run\", value = 1 }\n");
  EXPECT_EQ(p.common.run_forward->point, *p.find("run"));
}

TEST(Bindings, TheSetpointIsAHoldingPointOfOneOrTwoRegisters) {
  const auto setpoint = [](const std::string& table, const std::string& type) {
    return kHead + point("r", table, 0, type) + "[common]\nsetpoint_rpm = \"r\"\n";
  };
  EXPECT_EQ(parsed(setpoint("holding", "u32")).common.setpoint_rpm, 0u);
  EXPECT_EQ(parsed(setpoint("holding", "s32")).common.setpoint_rpm, 0u);
  EXPECT_EQ(parsed(setpoint("holding", "f32")).common.setpoint_rpm, 0u);
  expect_refused(
      errors_of,
      {{setpoint("input", "u32"),
        {"common.setpoint_rpm: 'r' must be a holding point of type u16, s16, u32, s32 or f32"}},
       {setpoint("coil", "bit"), {"'r' must be a holding point of type u16, s16, u32, s32"}}});
}

// run_reverse as a drive with a direction coil and a run coil takes it: direction, then run.
const std::string kCoilDrive = kHead + point("run_coil", "coil", 0, "bit") +  // 4-8
                               point("direction_coil", "coil", 1, "bit") +    // 9-13
                               point("control", "holding", 5, "u16") +        // 14-18
                               point("state", "input", 6, "u16");             // 19-23

TEST(Bindings, ASequencesItemsMayNameTheirOwnPoints) {
  const Profile p = parsed(
      kCoilDrive +
      "[common]\nstop = { point = \"run_coil\", value = 0 }\n"
      "run_forward = { sequence = [{ point = \"direction_coil\", value = 0 }, "
      "{ point = \"run_coil\", value = 1 }] }\n"
      "run_reverse = { point = \"control\", sequence = [{ point = \"direction_coil\", value = 1 }, "
      "6, { point = \"run_coil\", value = 1 }] }\n");
  const CommonBindings& c = p.common;
  ASSERT_TRUE(c.run_forward && c.run_reverse && c.stop);
  EXPECT_THAT(c.run_forward->points, ElementsAre(*p.find("direction_coil"), *p.find("run_coil")));
  EXPECT_THAT(c.run_forward->sequence, ElementsAre(0, 1));
  EXPECT_EQ(c.run_forward->point, *p.find("run_coil"));  // the last step's
  EXPECT_EQ(c.run_forward->value, 1);
  EXPECT_THAT(c.run_reverse->points,
              ElementsAre(*p.find("direction_coil"), *p.find("control"), *p.find("run_coil")));
  EXPECT_THAT(c.run_reverse->sequence, ElementsAre(1, 6, 1));
  EXPECT_THAT(c.stop->points, ElementsAre(*p.find("run_coil")));
}

TEST(Bindings, ASequenceItemMustNameAPointACommandCanWrite) {
  const auto run = [](const std::string& binding) {
    return errors_of(kCoilDrive + "[common]\nstop = { point = \"run_coil\", value = 0 }\n" +
                     "run_forward = " + binding + "\n");
  };
  expect_refused(
      run,
      {{"{ sequence = [{ point = \"nowhere\", value = 1 }] }",
        {"p.toml:26: common.run_forward.sequence.point: no point is called 'nowhere'"}},
       {"{ sequence = [{ point = \"state\", value = 1 }] }",
        {"common.run_forward.sequence.point: 'state' must be a one-register holding point or a "
         "coil"}},
       {"{ sequence = [{ point = \"run_coil\", value = 2 }] }",
        {"common.run_forward.sequence.value: 'run_coil' is a coil: it is written 0 or 1 (got 2)"}},
       {"{ sequence = [{ point = \"run_coil\" }] }",
        {"common.run_forward.sequence.value: required key is missing"}},
       {"{ sequence = [{ point = \"run_coil\", value = 1, spare = 1 }] }",
        {"common.run_forward.sequence.spare: unknown key"}},
       // A plain number needs the binding's point.
       {"{ sequence = [{ point = \"direction_coil\", value = 0 }, 1] }",
        {"common.run_forward.point: required key is missing"}},
       // A plain number to a coil is 0 or 1 too.
       {"{ point = \"run_coil\", sequence = [0, 0xFF00] }",
        {"common.run_forward.sequence: 'run_coil' is a coil: it is written 0 or 1 (got 65280)"}},
       {"{ sequence = [{ point = \"run_coil\", value = 1 }, \"on\"] }",
        {"common.run_forward.point: required key is missing",
         "common.run_forward.sequence: must be 1..4 values 0..65535"}},
       {"{ sequence = [{ point = \"run_coil\", value = 1 }, { point = \"run_coil\", "
        "value = 0 }, { point = \"run_coil\", value = 1 }, { point = \"run_coil\", "
        "value = 0 }, { point = \"run_coil\", value = 1 }] }",
        {"common.run_forward.sequence: must be 1..4 values"}},
       {"{ sequence = [] }",
        {"common.run_forward.point: required key is missing",
         "common.run_forward.sequence: must be 1..4 values"}}});
}

// ---- The driver, by hand: the frames on the wire

Bytes frame(std::vector<std::uint8_t> pdu) {
  return encode(Framing::rtu, kSlave, pdu);
}

class BindingsDriver : public DriverAtHand {
 protected:
  explicit BindingsDriver(const std::string& text = kDrive) : DriverAtHand(kSlave, parsed(text)) {}
  void answer(const Bytes& wire) { EXPECT_NE(d.on_receive(wire, now).kind, RxKind::foreign); }

  // One poll cycle: the coils, the trip bits, the speed, the reference, and the status and
  // warning registers whose masked points are read in one request.
  void cycle(std::uint16_t status, std::uint16_t trips = 0, std::uint8_t coils = 0,
             std::uint16_t speed = 0, std::uint16_t warning = 0) {
    ASSERT_EQ(sent(), frame(read_pdu(0x01, 0, 2)));
    answer(frame({0x01, 0x01, coils}));
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 20, 1)));
    answer(frame(words_pdu(0x04, {trips})));
    ASSERT_EQ(sent(), frame(read_pdu(0x04, 30, 1)));
    answer(frame(words_pdu(0x04, {speed})));
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 0, 2)));
    answer(frame(words_pdu(0x03, {0, 0})));
    ASSERT_EQ(sent(), frame(read_pdu(0x03, 10, 2)));
    answer(frame(words_pdu(0x03, {status, warning})));
    now += 500ms;
  }

  const Value& value(std::string_view name) {
    for (std::size_t i = 0; i < d.points().size(); ++i) {
      if (d.points()[i].name == name) return d.values()[i];
    }
    ADD_FAILURE() << "no point " << name;
    static const Value none;
    return none;
  }
};

TEST_F(BindingsDriver, MaskedPointsShareARegisterReadOnce) {
  // Status 0x0209: fault number 2 (over_current) in the high byte, tripped (bit 3) and running
  // forward (bit 0) in the low one; warning 0x2A in the high byte of 11, mode 5 in its low nibble.
  cycle(0x0209, 0, 0, 0, 0x2AF5);
  EXPECT_TRUE(d.common().ready);
  EXPECT_TRUE(d.common().faults.has(Fault::over_current));
  EXPECT_EQ(d.common().native_fault, 2u);
  EXPECT_EQ(std::get<std::int64_t>(value("warning")), 0x2A);
  EXPECT_EQ(std::get<std::int64_t>(value("mode")), 5);  // 0xF5 & 0x0F: the 0xF0 bits are no one's
  EXPECT_EQ(d.points()[0].name, "warning");
  // The masked points are read-only at the PLC, whatever their table.
  for (const char* name : {"warning", "mode"}) {
    const auto& spec = *std::find_if(d.points().begin(), d.points().end(),
                                     [&](const PointSpec& s) { return s.name == name; });
    EXPECT_EQ(spec.write_level, PointSpec::WriteLevel::none) << name;
  }
  // And a write to one is refused before it reaches the line.
  const auto at = static_cast<std::size_t>(
      std::find_if(d.points().begin(), d.points().end(),
                   [](const PointSpec& s) { return s.name == "warning"; }) -
      d.points().begin());
  const WriteOp op = WriteOp::of_point(at, std::int64_t{1});
  EXPECT_EQ(d.check(std::span(&op, 1)), WriteCheck::invalid_value);
}

TEST_F(BindingsDriver, RunningIsAnyOfItsBits) {
  cycle(0x0000);
  EXPECT_FALSE(d.common().running);
  cycle(0x0002);  // reverse-running bit
  EXPECT_TRUE(d.common().running);
  cycle(0x0001);  // forward-running bit
  EXPECT_TRUE(d.common().running);
  cycle(0xFF04);  // fault number 255, bit 2 (neither run bit), no trip bit: not running
  EXPECT_FALSE(d.common().running);
  EXPECT_TRUE(d.common().faults.empty());  // the trip bit says whether a fault is active
  EXPECT_EQ(d.common().native_fault, 255u);
}

TEST_F(BindingsDriver, CommandsAreFc05ToTheCoilAndTheSetpointFc16OfTwoRegisters) {
  cycle(0x0000);
  const WriteOp ops[] = {WriteOp::of_command(Command::run_forward), WriteOp::of_setpoint(1500)};
  ASSERT_EQ(d.check(ops), WriteCheck::ok);
  ASSERT_EQ(d.apply(ops[1], 1, now), WriteStatus::pending);
  ASSERT_EQ(d.apply(ops[0], 2, now), WriteStatus::pending);
  // 1500 rpm at 0.01: raw 150000 = 0x000249F0, high word first, FC 16 although [modbus] write
  // is "single" (FC 06 writes one register).
  const Bytes setpoint = frame({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x00, 0x02, 0x49, 0xF0});
  ASSERT_EQ(sent(), setpoint);
  answer(frame({0x10, 0x00, 0x00, 0x00, 0x02}));
  EXPECT_EQ(d.common().setpoint_rpm, 1500);
  // Run: coil 0 ON (FC 05, 0xFF00), echoed.
  const Bytes run = frame({0x05, 0x00, 0x00, 0xFF, 0x00});
  ASSERT_EQ(sent(), run);
  answer(run);
  EXPECT_EQ(d.common().command, Command::run_forward);
  // Stop: coil 0 OFF; reset: coil 1 ON.
  const WriteOp stop = WriteOp::of_command(Command::stop);
  ASSERT_EQ(d.apply(stop, 3, now), WriteStatus::pending);
  ASSERT_EQ(sent(), frame({0x05, 0x00, 0x00, 0x00, 0x00}));
  answer(frame({0x05, 0x00, 0x00, 0x00, 0x00}));
  EXPECT_EQ(d.common().command, Command::stop);
  const WriteOp reset = WriteOp::of_command(Command::reset_fault);
  ASSERT_EQ(d.apply(reset, 4, now), WriteStatus::pending);
  ASSERT_EQ(sent(), frame({0x05, 0x00, 0x01, 0xFF, 0x00}));
  // A setpoint the two registers carry but a u16 would not: 700 rpm is raw 70000.
  const WriteOp big = WriteOp::of_setpoint(700);
  ASSERT_EQ(d.apply(big, 5, now), WriteStatus::pending);
  answer(frame({0x05, 0x00, 0x01, 0xFF, 0x00}));
  EXPECT_EQ(sent(), frame({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x00, 0x01, 0x11, 0x70}));
}

FaultSet only(Fault f) {
  FaultSet s;
  s.set(f);
  return s;
}

class TripBitsDriver : public BindingsDriver {
 protected:
  TripBitsDriver() : BindingsDriver(with_trip_bits()) {}
};

TEST_F(TripBitsDriver, TheLowestNamedBitSetIsTheFault) {
  cycle(0, 0x0000);
  EXPECT_TRUE(d.common().faults.empty());
  EXPECT_EQ(d.common().native_fault, 0u);
  cycle(0, 0x0006);  // bits 1 (over_voltage) and 2 (not named)
  EXPECT_EQ(d.common().faults, only(Fault::over_voltage));
  EXPECT_EQ(d.common().native_fault, 6u);  // the register's value
  cycle(0, 0x0013);                        // bits 0, 1, 4: the lowest named wins
  EXPECT_EQ(d.common().faults, only(Fault::over_current));
  cycle(0, 0x0010);
  EXPECT_EQ(d.common().faults, only(Fault::under_voltage));
  cycle(0, 0x8004);  // bits set, none named: other (the profile's hardware_fault)
  EXPECT_EQ(d.common().faults, only(Fault::hardware_fault));
  EXPECT_EQ(d.common().native_fault, 0x8004u);
}

// A drive of two coils: run reverse is the direction coil ON, then the run coil ON.
const std::string kTwoCoils =
    kCoilDrive +
    "[common]\nrunning = { point = \"state\", any_bit = [0, 1] }\n"
    "stop = { point = \"run_coil\", value = 0 }\n"
    "run_forward = { sequence = [{ point = \"direction_coil\", value = 0 }, "
    "{ point = \"run_coil\", value = 1 }] }\n"
    "run_reverse = { sequence = [{ point = \"direction_coil\", value = 1 }, "
    "{ point = \"run_coil\", value = 1 }] }\n";

TEST(BindingsSequence, EachStepGoesToItsOwnCoilAndAStopOvertakesTheRest) {
  ModbusDriver d = support::driver_of(kSlave, parsed(kTwoCoils));
  TimePoint now = TimePoint{} + 10s;
  const auto sent = [&] {
    const auto ex = d.next_exchange(now);
    return ex ? ex->frame : Bytes{};
  };
  const WriteOp reverse = WriteOp::of_command(Command::run_reverse);
  ASSERT_EQ(d.apply(reverse, 1, now), WriteStatus::pending);
  const Bytes direction_on = frame({0x05, 0x00, 0x01, 0xFF, 0x00});
  ASSERT_EQ(sent(), direction_on);
  d.on_receive(direction_on, now);
  const Bytes run_on = frame({0x05, 0x00, 0x00, 0xFF, 0x00});
  ASSERT_EQ(sent(), run_on);
  d.on_receive(run_on, now);
  EXPECT_EQ(d.common().command, Command::run_reverse);
  std::vector<Completion> done;
  d.take_completions(done);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].result, WriteResult::ok);
  // Run forward, and a stop while its first step is on the line: the stop writes the run coil,
  // which the run's second step would, so the run ends at its first step and the stop goes.
  const WriteOp forward = WriteOp::of_command(Command::run_forward);
  ASSERT_EQ(d.apply(forward, 2, now), WriteStatus::pending);
  const Bytes direction_off = frame({0x05, 0x00, 0x01, 0x00, 0x00});
  ASSERT_EQ(sent(), direction_off);
  const WriteOp stop = WriteOp::of_command(Command::stop);
  ASSERT_EQ(d.apply(stop, 3, now), WriteStatus::pending);
  d.on_receive(direction_off, now);
  const Bytes run_off = frame({0x05, 0x00, 0x00, 0x00, 0x00});
  ASSERT_EQ(sent(), run_off);  // never the run coil ON
  d.on_receive(run_off, now);
  EXPECT_EQ(d.common().command, Command::stop);
  done.clear();
  d.take_completions(done);
  ASSERT_EQ(done.size(), 2u);
  EXPECT_EQ(done[0].result, WriteResult::no_response);
  EXPECT_EQ(done[1].result, WriteResult::ok);
}

// ---- The simulator serves the bindings

Bytes request(ModbusSimulator& sim, std::vector<std::uint8_t> pdu) {
  const Bytes reply = sim.on_receive(frame(std::move(pdu)), TimePoint{} + 1s);
  return reply;
}

TEST(BindingsSimulator, ACoilStartsTheDriveAndAMaskedFaultReadsBackInItsByte) {
  ModbusSimulator sim(kSlave, parsed(kDrive));
  // The reference, 1200 rpm (raw 120000 = 0x0001D4C0), then coil 0 ON.
  const std::vector<std::uint8_t> reference = {0x10, 0x00, 0x00, 0x00, 0x02,
                                               0x04, 0x00, 0x01, 0xD4, 0xC0};
  EXPECT_EQ(request(sim, reference), frame({0x10, 0x00, 0x00, 0x00, 0x02}));
  EXPECT_EQ(request(sim, {0x05, 0x00, 0x00, 0xFF, 0x00}), frame({0x05, 0x00, 0x00, 0xFF, 0x00}));
  EXPECT_THAT(sim.control("state", {}), HasSubstr("running forward"));
  EXPECT_EQ(request(sim, read_pdu(0x03, 10, 1)), frame(words_pdu(0x03, {0x0001})));  // bit 0
  EXPECT_EQ(request(sim, read_pdu(0x04, 30, 1)), frame(words_pdu(0x04, {1200})));
  // A trip: the fault number in the high byte, the trip bit (3) in the low one, stopped.
  EXPECT_THAT(sim.control("fault 2", {}), HasSubstr("ok"));
  EXPECT_EQ(request(sim, read_pdu(0x03, 10, 1)), frame(words_pdu(0x03, {0x0208})));
  // A run while tripped does not start it; the reset coil clears the trip.
  request(sim, {0x05, 0x00, 0x00, 0xFF, 0x00});
  EXPECT_EQ(request(sim, read_pdu(0x03, 10, 1)), frame(words_pdu(0x03, {0x0208})));
  EXPECT_EQ(request(sim, {0x05, 0x00, 0x01, 0xFF, 0x00}), frame({0x05, 0x00, 0x01, 0xFF, 0x00}));
  EXPECT_EQ(request(sim, read_pdu(0x03, 10, 1)), frame(words_pdu(0x03, {0x0000})));
  // Coil 0 OFF stops it.
  request(sim, {0x05, 0x00, 0x00, 0xFF, 0x00});
  EXPECT_THAT(sim.control("state", {}), HasSubstr("running forward"));
  request(sim, {0x05, 0x00, 0x00, 0x00, 0x00});
  EXPECT_THAT(sim.control("state", {}), HasSubstr("stopped"));
  // A coil written with neither ON nor OFF is refused (Application Protocol 6.5).
  EXPECT_EQ(request(sim, {0x05, 0x00, 0x00, 0x00, 0x01}), frame({0x85, 0x03}));
  // `set` of a masked point changes its bits only.
  ASSERT_THAT(sim.control("raw holding 11 0xFFFF", {}), HasSubstr("ok"));
  EXPECT_THAT(sim.control("set warning 3", {}), HasSubstr("ok"));
  EXPECT_EQ(request(sim, read_pdu(0x03, 11, 1)), frame(words_pdu(0x03, {0x03FF})));
  EXPECT_THAT(sim.control("set mode 16", {}), HasSubstr("error"));  // beyond its four bits
}

TEST(BindingsSimulator, ReverseRunningShowsInTheSecondBit) {
  // run_reverse as a coil of its own (a drive with FWD and REV run coils).
  std::string text = replaced(kDrive, "reset_fault = { point = \"reset_coil\", value = 1 }\n",
                              "run_reverse = { point = \"reset_coil\", value = 1 }\n");
  ModbusSimulator sim(kSlave, parsed(text));
  request(sim, {0x05, 0x00, 0x01, 0xFF, 0x00});
  EXPECT_THAT(sim.control("state", {}), HasSubstr("running reverse"));
  EXPECT_EQ(request(sim, read_pdu(0x03, 10, 1)), frame(words_pdu(0x03, {0x0002})));
}

TEST(BindingsSimulator, ASequenceOverTwoCoilsIsItsCommandOnlyWhenBothHoldItsValues) {
  ModbusSimulator sim(kSlave, parsed(kTwoCoils));
  request(sim, {0x05, 0x00, 0x01, 0xFF, 0x00});  // direction ON: nothing yet
  EXPECT_THAT(sim.control("state", {}), HasSubstr("stopped"));
  request(sim, {0x05, 0x00, 0x00, 0xFF, 0x00});  // run ON with direction ON: reverse
  EXPECT_THAT(sim.control("state", {}), HasSubstr("running reverse"));
  EXPECT_EQ(request(sim, read_pdu(0x04, 6, 1)), frame(words_pdu(0x04, {0x0002})));
  request(sim, {0x05, 0x00, 0x00, 0x00, 0x00});  // stop
  request(sim, {0x05, 0x00, 0x01, 0x00, 0x00});
  request(sim, {0x05, 0x00, 0x00, 0xFF, 0x00});  // direction OFF, run ON: forward
  EXPECT_THAT(sim.control("state", {}), HasSubstr("running forward"));
}

TEST(BindingsSimulator, AFaultCodeBitFieldIsTheNativeCode) {
  ModbusSimulator sim(kSlave, parsed(with_trip_bits()));
  sim.control("fault 6", {});
  EXPECT_EQ(request(sim, read_pdu(0x04, 20, 1)), frame(words_pdu(0x04, {0x0006})));
}

// ---- On the bus engine: what a PLC reads

TEST(BindingsOnTheBus, ThePlcRunsTheDriveThroughItsCoilAndReadsItsMaskedFault) {
  const ProfileFile file(kDrive);
  test::AdapterBench b(drivegate_adapter, {.options = {{"profile", file.path}}});
  ASSERT_TRUE(b.until_online());
  ASSERT_TRUE(b.run_forward_at(1200));
  EXPECT_TRUE(b.until_reads("speed_rpm", 1200, 2000ms));
  EXPECT_TRUE(b.rig.run_until([&] { return (b.status() & kRunning) != 0; }, 2s));
  EXPECT_THAT(b.control("state"), HasSubstr("run_coil = 1"));
  EXPECT_THAT(b.control("state"), HasSubstr("reference = 1200"));
  // The reverse-running bit alone is running too.
  ASSERT_THAT(b.control("raw holding 10 0x0002"), HasSubstr("ok"));
  b.rig.run_for(1500ms);
  EXPECT_NE(b.status() & kRunning, 0u);
  // A trip: the fault number in the high byte of the status register.
  ASSERT_THAT(b.control("fault 2"), HasSubstr("ok"));
  EXPECT_TRUE(b.until_reads("fault_code", static_cast<std::uint32_t>(Fault::over_current), 2000ms));
  EXPECT_EQ(b.read("native_fault"), 2u);
  EXPECT_NE(b.status() & kFaulted, 0u);
  EXPECT_EQ(b.status() & kRunning, 0u);
  EXPECT_EQ(b.write({cmd::reset_fault}), Outcome::ok);
  EXPECT_TRUE(b.until_reads("fault_code", 0, 2000ms));
  // The masked points of register 11 as the PLC reads them, and refused to its writes.
  ASSERT_THAT(b.control("raw holding 11 0x2AF5"), HasSubstr("ok"));
  b.rig.run_for(1500ms);
  EXPECT_EQ(b.read("warning"), 0x2Au);
  EXPECT_EQ(b.read("mode"), 5u);
  EXPECT_EQ(b.write("warning", {1}), Outcome::no_such_point);
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_TRUE(b.until_reads("speed_rpm", 0, 2000ms));
  EXPECT_THAT(b.control("state"), HasSubstr("run_coil = 0"));
}

TEST(BindingsOnTheBus, ATripBitFieldIsTheUnifiedFaultAndItsValueTheNativeOne) {
  const ProfileFile file(with_trip_bits());
  test::AdapterBench b(drivegate_adapter, {.options = {{"profile", file.path}}});
  ASSERT_TRUE(b.until_online());
  ASSERT_THAT(b.control("fault 6"), HasSubstr("ok"));  // bits 1 and 2
  EXPECT_TRUE(b.until_reads("fault_code", static_cast<std::uint32_t>(Fault::over_voltage), 2000ms));
  EXPECT_EQ(b.read("native_fault"), 6u);
  EXPECT_NE(b.status() & kFaulted, 0u);
}

// ---- While the drive runs, a run command does not take it out of its running state

// A CiA 402-like drive: the control word at holding 0 (6 shutdown, 7 switch on, 15 enable
// operation, 0x080F the same in reverse), its state at input 1 as codes (1 running forward, 2
// reverse, 3 tripped), its speed at input 2. The way into operation is 6, 7, 15; from a
// running drive, 6 would switch the power stage off and the motor coast.
const std::string kStateMachine =
    "[profile]\nname = \"cia\"\nsource = \"a test\"\n"
    "[[point]]\nname = \"control\"\ntable = \"holding\"\naddress = 0\ntype = \"u16\"\n"
    "[[point]]\nname = \"state\"\ntable = \"input\"\naddress = 1\ntype = \"u16\"\n"
    "[[point]]\nname = \"speed\"\ntable = \"input\"\naddress = 2\ntype = \"s16\"\n"
    "[[point]]\nname = \"reference\"\ntable = \"holding\"\naddress = 3\ntype = \"s16\"\n"
    "[common]\nspeed_rpm = \"speed\"\nsetpoint_rpm = \"reference\"\n"
    "running = { point = \"state\", any_value = [1, 2] }\n"
    "fault = { point = \"state\", any_value = [3] }\n"
    "stop = { point = \"control\", sequence = [0x0007] }\n"
    "run_forward = { point = \"control\", sequence = [0x0006, 0x0007, 0x000F] }\n"
    "run_reverse = { point = \"control\", sequence = [0x0006, 0x0007, 0x080F] }\n"
    "reset_fault = { point = \"control\", sequence = [0x0080, 0x0006] }\n";

// The driver against the simulator of the same profile: every exchange until the driver has
// nothing to send for a while; the frames it sent (the requests).
struct AgainstItsSimulator {
  explicit AgainstItsSimulator(const std::string& text)
      : d{support::driver_of(kSlave, parsed(text))}, sim{kSlave, parsed(text)} {}

  std::vector<Bytes> pump(std::chrono::milliseconds for_how_long = 1200ms) {
    std::vector<Bytes> sent;
    const TimePoint until = now + for_how_long;
    while (now < until) {
      const auto ex = d.next_exchange(now);
      if (!ex) {
        now += 10ms;
        continue;
      }
      sent.push_back(ex->frame);
      const Bytes reply = sim.on_receive(ex->frame, now);
      if (!reply.empty()) d.on_receive(reply, now);
      now += 5ms;
    }
    return sent;
  }
  // The writes among them: FC 05, 06 and 16.
  std::vector<Bytes> writes(std::chrono::milliseconds for_how_long = 1200ms) {
    std::vector<Bytes> out;
    for (Bytes& f : pump(for_how_long)) {
      if (f.size() > 1 && (f[1] == 0x05 || f[1] == 0x06 || f[1] == 0x10)) out.push_back(f);
    }
    return out;
  }
  void command(Command c) {
    const WriteOp op = WriteOp::of_command(c);
    ASSERT_EQ(d.apply(op, ++ticket, now), WriteStatus::pending);
  }

  ModbusDriver d;
  ModbusSimulator sim;
  TimePoint now = TimePoint{} + 10s;
  Ticket ticket = 0;
};

Bytes write_control(std::uint16_t value) {
  return frame({0x06, 0x00, 0x00, static_cast<std::uint8_t>(value >> 8),
                static_cast<std::uint8_t>(value & 0xFF)});
}

TEST(BindingsSequence, WhileTheDriveRunsOnlyARunsLastStepOnItsPointIsWritten) {
  AgainstItsSimulator rig(kStateMachine);
  rig.pump();
  ASSERT_TRUE(rig.d.common().ready);
  ASSERT_FALSE(rig.d.common().running);
  // Stopped: the whole way in.
  rig.command(Command::run_forward);
  EXPECT_THAT(rig.writes(),
              ElementsAre(write_control(0x0006), write_control(0x0007), write_control(0x000F)));
  ASSERT_TRUE(rig.d.common().running);
  // Running forward, reverse: the running state's own word, never 6 (power stage off) first.
  rig.command(Command::run_reverse);
  EXPECT_THAT(rig.writes(), ElementsAre(write_control(0x080F)));
  EXPECT_TRUE(rig.d.common().running);
  EXPECT_EQ(rig.d.common().command, Command::run_reverse);
  // A stop is written whole, running or not.
  rig.command(Command::stop);
  EXPECT_THAT(rig.writes(), ElementsAre(write_control(0x0007)));
  EXPECT_FALSE(rig.d.common().running);
  // Stopped again: the whole way in again.
  rig.command(Command::run_forward);
  EXPECT_THAT(rig.writes(),
              ElementsAre(write_control(0x0006), write_control(0x0007), write_control(0x000F)));
}

TEST(BindingsSequence, WhileTheDriveRunsStepsOnOtherPointsAreStillWritten) {
  // The direction coil before the run coil: from a drive running forward, run reverse must
  // still turn the direction coil ON; only steps on the run coil's own point are the way in.
  AgainstItsSimulator rig(kTwoCoils);
  rig.pump();
  rig.command(Command::run_forward);
  rig.pump();
  ASSERT_TRUE(rig.d.common().running);
  rig.command(Command::run_reverse);
  EXPECT_THAT(rig.writes(), ElementsAre(frame({0x05, 0x00, 0x01, 0xFF, 0x00}),
                                        frame({0x05, 0x00, 0x00, 0xFF, 0x00})));
  EXPECT_EQ(rig.d.common().command, Command::run_reverse);
}

// ---- States as codes: any_value

TEST(Bindings, AnyValueIsOneToSixteenCodesOfAOneRegisterPoint) {
  const auto text = [](const std::string& binding) {
    return std::string(
               "[profile]\nname = \"codes\"\nsource = \"a test\"\n"
               "[[point]]\nname = \"state\"\ntable = \"input\"\naddress = 1\ntype = \"u16\"\n"
               "[[point]]\nname = \"low\"\ntable = \"input\"\naddress = 2\ntype = \"u16\"\n"
               "mask = 0x000F\n"
               "[[point]]\nname = \"wide\"\ntable = \"input\"\naddress = 4\ntype = \"u32\"\n"
               "[common]\nrunning = ") +
           binding + "\n";
  };
  const auto common = [&](const std::string& binding) { return errors_of(text(binding)); };
  const Profile p = parsed(text("{ point = \"state\", any_value = [1, 2] }"));
  ASSERT_TRUE(p.common.running);
  EXPECT_THAT(p.common.running->values, ElementsAre(1, 2));
  EXPECT_TRUE(p.common.running->bits.empty());
  EXPECT_THAT(parsed(text("{ point = \"low\", any_value = [15] }")).common.running->values,
              ElementsAre(15));
  expect_refused(
      common, {{"{ point = \"low\", any_value = [16] }",
                {"p.toml:21: common.running.any_value: values are numbers 0..15 of 'low'"}},
               {"{ point = \"state\", any_value = [1, 1] }",
                {"common.running.any_value: 1 is listed twice"}},
               {"{ point = \"state\", any_value = [] }",
                {"common.running.any_value: must be a list of 1..16"}},
               {"{ point = \"state\", any_value = [\"1\"] }",
                {"common.running.any_value: values are numbers 0..65535"}},
               {"{ point = \"state\", bit = 0, any_value = [1] }",
                {"common.running.bit: bit or any_value, not both"}},
               {"{ point = \"wide\", any_value = [1] }", {"'wide' must be a one-register point"}}});
}

TEST(BindingsSimulator, StateCodesFollowTheDriveAndLeaveEachOthersCodeAlone) {
  AgainstItsSimulator rig(kStateMachine);
  rig.pump();
  EXPECT_FALSE(rig.d.common().running);
  EXPECT_TRUE(rig.d.common().faults.empty());
  rig.command(Command::run_reverse);
  rig.pump();
  EXPECT_TRUE(rig.d.common().running);  // state 2, the second code listed
  EXPECT_THAT(rig.sim.control("state", rig.now), HasSubstr("running reverse"));
  rig.sim.control("fault 5", rig.now);
  rig.pump();
  EXPECT_FALSE(rig.d.common().running);  // a trip stops the output: state 3
  EXPECT_FALSE(rig.d.common().faults.empty());
  rig.sim.control("fault 0", rig.now);
  rig.pump();
  EXPECT_TRUE(rig.d.common().faults.empty());  // state 0: neither running nor tripped
  EXPECT_FALSE(rig.d.common().running);
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_bindings_test
