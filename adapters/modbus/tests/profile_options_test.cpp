// Device options a profile declares ([options.NAME]), the speed in rpm through them
// (rpm_factor), and commands written as sequences: parsed, evaluated with numbers worked by hand,
// and the frames the driver sends for them, by hand and on the bus engine against the simulator.
#include "profile_options.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "driver.h"
#include "plugin/adapter_options.h"
#include "profile.h"
#include "profile_support.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;
using namespace support;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr std::uint8_t kSlave = 7;

// span-drive (profiles/span-drive.toml), the Vacon / Eaton M-Max kind: the reference 0..10000
// is 0..100 % of the span between the minimum and the maximum frequency, and so is the actual
// speed. Worked by hand at the defaults (10 Hz .. 50 Hz, 4 poles, 30 rpm a Hz): raw 0 = 10 Hz =
// 300 rpm, raw 10000 = 50 Hz = 1500 rpm, 0.12 rpm a raw step: raw 5000 = 30 Hz = 900 rpm.
const std::string kSpanProfile = profile_text(DRIVEGATE_TEST_PROFILE_DIR, "span-drive");

// kSpanProfile with `from` replaced by `to`.
std::string span_with(const std::string& from, const std::string& to) {
  return support::replaced(kSpanProfile, from, to);
}

// kHzProfile with `from` replaced by `to`.
std::string hz_with(const std::string& from, const std::string& to) {
  return support::replaced(kHzProfile, from, to);
}

Bytes frame(std::vector<std::uint8_t> pdu) {
  return encode(Framing::rtu, kSlave, pdu);
}
Bytes fc06(std::uint16_t address, std::uint16_t value) {
  return support::fc06_frame(kSlave, address, value);
}

ModbusDriver driver_of(Profile p) {
  return support::driver_of(kSlave, std::move(p));
}

// --- [options.NAME] ---

TEST(ProfileOptions, AreReadWithTheirRangesAndDefaults) {
  const Profile p = parsed(kHzProfile);
  ASSERT_EQ(p.options.size(), 2u);
  const ProfileOption& poles = p.options[*p.find_option("motor_poles")];
  EXPECT_EQ(poles.value, 4);
  EXPECT_EQ(poles.min, 2);
  EXPECT_EQ(poles.max, 48);
  EXPECT_EQ(p.options[*p.find_option("max_frequency_hz")].unit, "Hz");
  EXPECT_EQ(options_text(p), "max_frequency_hz = 50 (default), motor_poles = 4 (default)");
}

TEST(ProfileOptions, BadDeclarationsAreErrorsOnTheirLines) {
  expect_refused(errors_of, {{hz_with("default = 4\n", "default = 50\n"),
                              {"p.toml:6: options.motor_poles.default: must be in min..max"}},
                             {hz_with("min = 2\nmax = 48", "min = 48\nmax = 2"),
                              {"options.motor_poles.min: must be below max"}},
                             {hz_with("description = \"motor poles (nameplate)\"\n", ""),
                              {"options.motor_poles.description: required key is missing"}}});
  EXPECT_THAT(errors_of(hz_with("[options.motor_poles]", "[options.attempts]")),
              testing::Contains(HasSubstr("'attempts' is an option of the modbus adapter itself")));
  EXPECT_THAT(errors_of(hz_with("[options.motor_poles]", "[options.Motor]")),
              testing::Contains(HasSubstr("snake_case")));
  expect_refused(errors_of, {{hz_with("default = 4\n", "default = \"four\"\n"),
                              {"options.motor_poles.default: must be a number"}},
                             {hz_with("default = 4\n", "default = nan\n"),
                              {"options.motor_poles.default: must be in"}}});
}

TEST(ProfileOptions, ADevicesValuesAreCheckedAgainstTheRange) {
  Profile p = parsed(kHzProfile);
  Options o;
  std::string error;
  o.set("motor_poles", 60.0);
  EXPECT_FALSE(apply_options(p, o, error));
  EXPECT_EQ(error, "option motor_poles: must be a number in 2..48 (got 60)");
  o.set("motor_poles", std::string("two"));
  EXPECT_FALSE(apply_options(p, o, error));
  o.set("motor_poles", 2.0);
  EXPECT_TRUE(apply_options(p, o, error)) << error;
  EXPECT_EQ(p.options[*p.find_option("motor_poles")].value, 2);
}

// --- rpm_factor ---

TEST(RpmFactor, IsAProductAndQuotientOfNumbersAndOptions) {
  const Profile p = parsed(kPercentProfile);
  // 50 Hz x 120 / 4 poles / 100 %: 15 rpm per %.
  EXPECT_DOUBLE_EQ(factor_value(p.common.speed_factor, p.options), 15.0);
  const Profile hz = parsed(kHzProfile);
  EXPECT_DOUBLE_EQ(factor_value(hz.common.speed_factor, hz.options), 30.0);
  EXPECT_DOUBLE_EQ(factor_value(RpmFactor{}, hz.options), 1.0);  // the old form: rpm
}

TEST(RpmFactor, WhatIsNotOneIsAnErrorThatSaysWhy) {
  const Profile p = parsed(kHzProfile);
  const auto why = [&](std::string_view text) {
    std::string w;
    EXPECT_FALSE(parse_rpm_factor(text, p.options, w)) << text;
    return w;
  };
  EXPECT_THAT(why(""), HasSubstr("is empty"));
  EXPECT_THAT(why("   "), HasSubstr("is empty"));
  EXPECT_THAT(why("0"), HasSubstr("0"));
  EXPECT_THAT(why("/"), HasSubstr("'/' where a number or an option name belongs"));
  EXPECT_THAT(why("a/b/"), HasSubstr("names 'a', which is not one of the profile's [options]"));
  EXPECT_THAT(why("120 / motor_poles /"), HasSubstr("ends in an operator"));
  EXPECT_THAT(why("motor_poles/0"), HasSubstr("divides by 0"));
  EXPECT_THAT(why("120 + motor_poles"), HasSubstr("no +, no - outside them"));
  EXPECT_THAT(why("120 - motor_poles"), HasSubstr("no +, no - outside them"));
  EXPECT_THAT(why("(120 / motor_poles)"),
              HasSubstr("has parentheses around something other than a difference"));
  EXPECT_THAT(why("120 motor_poles"), HasSubstr("where '*' or '/' belongs"));
  EXPECT_THAT(why("1.2.3"), HasSubstr("is not a number"));
  // An option whose range holds 0 could make the factor 0 or divide by it.
  EXPECT_THAT(errors_of(hz_with("min = 2\nmax = 48", "min = 0\nmax = 48")),
              testing::Contains(HasSubstr("option motor_poles can be 0 (its range is 0..48): the "
                                          "factor would divide by 0")));
  // In the profile: the key's line, the text quoted.
  EXPECT_THAT(errors_of(hz_with("rpm_factor = \"120 / motor_poles\" }\nsetpoint",
                                "rpm_factor = \"120 / poles\" }\nsetpoint")),
              ElementsAre(HasSubstr("common.speed_rpm.rpm_factor: '120 / poles' names 'poles'")));
}

// 4 poles at 50 Hz: 1500 rpm <-> 50.00 Hz <-> raw 5000 at 0.01 Hz.
TEST(RpmFactor, ASetpointOf1500RpmAt4PolesIs5000HundredthsOfAHertz) {
  EXPECT_EQ(setpoint_frame(driver_of(parsed(kHzProfile)), 1500), fc06(1, 5000));
  // 1000 rpm is 33.333 Hz: rounded to the point's step, 3333.
  EXPECT_EQ(setpoint_frame(driver_of(parsed(kHzProfile)), 1000), fc06(1, 3333));
  // Two poles: 1500 rpm is 25.00 Hz.
  const Profile two = with_options(parsed(kHzProfile), {{"motor_poles", 2}});
  EXPECT_EQ(setpoint_frame(driver_of(two), 1500), fc06(1, 2500));
}

TEST(RpmFactor, ASetpointBeyondThePointsRangeAfterConversionIsRefused) {
  // 32767 rpm at 2 poles is 546.12 Hz: above the reference's max of 400 Hz (exception 03).
  ModbusDriver d = driver_of(with_options(parsed(kHzProfile), {{"motor_poles", 2}}));
  WriteOp op = WriteOp::of_setpoint(32767);
  EXPECT_EQ(d.check(std::span(&op, 1)), WriteCheck::invalid_value);
  // 24000 rpm at 2 poles is 400.00 Hz: the edge, taken.
  op = WriteOp::of_setpoint(24000);
  EXPECT_EQ(d.check(std::span(&op, 1)), WriteCheck::ok);
  op = WriteOp::of_setpoint(24001);
  EXPECT_EQ(d.check(std::span(&op, 1)), WriteCheck::invalid_value);
  op = WriteOp::of_setpoint(-1);
  EXPECT_EQ(d.check(std::span(&op, 1)), WriteCheck::invalid_value);
}

TEST(RpmFactor, TheSpeedReadsInRpmThroughTheFactor) {
  ModbusDriver d = driver_of(parsed(kHzProfile));
  const TimePoint now = TimePoint{} + 10s;
  ASSERT_TRUE(d.next_exchange(now));
  // control 000F, reference 5000, status: running, output 49.83 Hz: 1494.9 rpm -> 1495.
  std::vector<std::uint8_t> pdu = {0x03, 8};
  for (const std::uint16_t w : std::initializer_list<std::uint16_t>{0x000F, 5000, 0x0002, 4983})
    put_be16(pdu, w);
  ASSERT_EQ(d.on_receive(frame(pdu), now).kind, RxKind::reply);
  EXPECT_EQ(d.common().speed_rpm, 1495);
  EXPECT_TRUE(d.common().running);
  EXPECT_EQ(d.common().setpoint_rpm, 1500);  // adopted: 50.00 Hz x 30
}

// A % of maximum, 16384 = 100 %: 1500 rpm at 4 poles and 50 Hz is 100 %, raw 16384 (0x4000).
TEST(RpmFactor, APercentOfMaximumFrequencyWith16384For100Percent) {
  const TimePoint now = TimePoint{} + 10s;
  EXPECT_EQ(setpoint_frame(driver_of(parsed(kPercentProfile)), 1500), fc06(1, 0x4000));
  EXPECT_EQ(setpoint_frame(driver_of(parsed(kPercentProfile)), 750), fc06(1, 0x2000));
  // 60 Hz maximum: 1800 rpm is 100 %.
  const Profile sixty = with_options(parsed(kPercentProfile), {{"max_frequency_hz", 60}});
  EXPECT_EQ(setpoint_frame(driver_of(sixty), 1800), fc06(1, 0x4000));
  // Read: 8192 is 50 %, 750 rpm; 65535 is 399.99 %, 6000 rpm... within range, but at 2 poles
  // and 400 Hz (120 rpm a %) 48000 rpm: beyond what speed_rpm carries, unknown and a fault.
  ModbusDriver r = driver_of(parsed(kPercentProfile));
  ASSERT_TRUE(r.next_exchange(now));
  std::vector<std::uint8_t> pdu = {0x03, 6};
  for (const std::uint16_t w : std::initializer_list<std::uint16_t>{1, 0x2000, 0x2000})
    put_be16(pdu, w);
  ASSERT_EQ(r.on_receive(frame(pdu), now).kind, RxKind::reply);
  EXPECT_EQ(r.common().speed_rpm, 750);
  ModbusDriver fast = driver_of(
      with_options(parsed(kPercentProfile), {{"motor_poles", 2}, {"max_frequency_hz", 400}}));
  ASSERT_TRUE(fast.next_exchange(now));
  pdu = {0x03, 6};
  for (const std::uint16_t w : std::initializer_list<std::uint16_t>{1, 0, 0xFFFF}) put_be16(pdu, w);
  ASSERT_EQ(fast.on_receive(frame(pdu), now).kind, RxKind::reply);
  EXPECT_TRUE(fast.common().speed_unknown);
  EXPECT_TRUE(fast.common().faults.has(Fault::sensor_fault));
}

// --- rpm_offset and a difference ---

TEST(RpmOffset, IsParsedWithTheDifferenceAndEvaluatedWithTheOptions) {
  const Profile p = parsed(kSpanProfile);
  ASSERT_TRUE(p.common.setpoint_offset);
  ASSERT_EQ(p.common.setpoint_factor.terms.size(), 4u);
  EXPECT_TRUE(p.common.setpoint_factor.terms[0].minus);
  // (50 - 10) x 120 / 4 / 10000 = 0.12 rpm a step; 10 x 120 / 4 = 300 rpm at raw 0.
  const RpmScale s = rpm_scale(p.common.setpoint_factor, p.common.setpoint_offset, p.options);
  EXPECT_DOUBLE_EQ(s.factor, 0.12);
  EXPECT_DOUBLE_EQ(s.offset, 300.0);
  EXPECT_DOUBLE_EQ(s.rpm(5000), 900.0);
  EXPECT_DOUBLE_EQ(s.value(300), 0.0);
  // 2 poles, 5..60 Hz: (60 - 5) x 60 / 10000 = 0.33 rpm a step, 300 rpm at raw 0.
  const Profile two =
      with_options(parsed(kSpanProfile),
                   {{"motor_poles", 2}, {"min_frequency_hz", 5}, {"max_frequency_hz", 60}});
  const RpmScale t = rpm_scale(two.common.setpoint_factor, two.common.setpoint_offset, two.options);
  EXPECT_DOUBLE_EQ(t.factor, 0.33);
  EXPECT_DOUBLE_EQ(t.offset, 300.0);
  // Without rpm_offset: none.
  const Profile hz = parsed(kHzProfile);
  EXPECT_FALSE(hz.common.setpoint_offset);
  EXPECT_DOUBLE_EQ(
      rpm_scale(hz.common.setpoint_factor, hz.common.setpoint_offset, hz.options).offset, 0.0);
}

TEST(RpmOffset, WhatIsNotOneIsAnErrorOnItsLine) {
  const Profile p = parsed(kSpanProfile);
  const auto why = [&](std::string_view text, bool offset = false) {
    std::string w;
    EXPECT_FALSE(offset ? parse_rpm_offset(text, p.options, w)
                        : parse_rpm_factor(text, p.options, w))
        << text;
    return w;
  };
  const std::string other = "has parentheses around something other than a difference";
  EXPECT_THAT(why("(max_frequency_hz - min_frequency_hz - 1)"), HasSubstr(other));
  EXPECT_THAT(why("(max_frequency_hz + min_frequency_hz)"), HasSubstr(other));
  EXPECT_THAT(why("(max_frequency_hz * 2)"), HasSubstr(other));
  EXPECT_THAT(why("(max_frequency_hz)"), HasSubstr(other));
  EXPECT_THAT(why("((max_frequency_hz - min_frequency_hz))"), HasSubstr(other));
  EXPECT_THAT(why("(max_frequency_hz - )"), HasSubstr(other));
  EXPECT_THAT(why("(max_frequency_hz - min_frequency_hz"), HasSubstr(other));
  EXPECT_THAT(why("(max_frequency_hz - (min_frequency_hz - 1))"), HasSubstr(other));
  EXPECT_THAT(why("(max_frequency_hz - poles)"), HasSubstr("names 'poles'"));
  EXPECT_THAT(why("(max_frequency_hz - min_frequency_hz) 2"), HasSubstr("where '*' or '/'"));
  EXPECT_THAT(why("2 (max_frequency_hz - min_frequency_hz)"), HasSubstr("where '*' or '/'"));
  EXPECT_THAT(why("max_frequency_hz - min_frequency_hz"), HasSubstr("no - outside them"));
  // Always 0: an option less itself, a number less itself.
  EXPECT_THAT(why("(motor_poles - motor_poles)"), HasSubstr("a difference that is always 0"));
  EXPECT_THAT(why("(50 - 50) * 2", true), HasSubstr("a difference that is always 0"));
  // Two numbers and a number less an option are differences too.
  std::string w;
  EXPECT_TRUE(parse_rpm_factor("(60 - 10) * 120 / motor_poles", p.options, w)) << w;
  EXPECT_TRUE(parse_rpm_offset("(0 - min_frequency_hz) * 120 / motor_poles", p.options, w)) << w;
  // An offset may be 0 (min_frequency_hz's range holds 0), but not divide by 0.
  EXPECT_TRUE(parse_rpm_offset("min_frequency_hz * 120 / motor_poles", p.options, w)) << w;
  EXPECT_THAT(why("120 / min_frequency_hz", true),
              HasSubstr("option min_frequency_hz can be 0 (its range is 0..320): the offset would "
                        "divide by 0"));
  // The options' defaults make the factor 0 or below: the profile's own error.
  EXPECT_THAT(
      errors_of(span_with("default = 50\nmin = 1", "default = 10\nmin = 1")),
      ElementsAre(
          HasSubstr("p.toml:43: common.speed_rpm.rpm_factor: '(max_frequency_hz - "
                    "min_frequency_hz) * 120 / motor_poles / 10000' is 0 with max_frequency_hz = "
                    "10, min_frequency_hz = 10, motor_poles = 4: a factor must be above 0 (the "
                    "options' defaults)"),
          HasSubstr("p.toml:44: common.setpoint_rpm.rpm_factor")));
  EXPECT_THAT(errors_of(span_with("default = 50\nmin = 1", "default = 5\nmin = 1")),
              testing::Contains(HasSubstr("is -0.015 with max_frequency_hz = 5")));
  // rpm_offset without rpm_factor, on speed_rpm's line.
  expect_refused(
      errors_of,
      {{span_with(
            "speed\", rpm_factor = \"(max_frequency_hz - min_frequency_hz) * 120 / motor_poles / "
            "10000\", rpm_offset",
            "speed\", rpm_offset"),
        {"p.toml:43: common.speed_rpm.rpm_offset: goes only with rpm_factor"}},
       // A bad offset: its own key and line.
       {span_with("rpm_offset = \"min_frequency_hz * 120 / motor_poles\" }\n"
                  "setpoint_rpm",
                  "rpm_offset = \"min_frequency_hz + 1\" }\nsetpoint_rpm"),
        {"p.toml:43: common.speed_rpm.rpm_offset: 'min_frequency_hz + 1' '+' where '*' or '/' "
         "belongs"}}});
}

// A device's options that make the span 0 or negative (maximum at or below minimum frequency)
// are refused when the device is made, saying which.
TEST(RpmOffset, ADevicesOptionsThatMakeTheFactorZeroOrNegativeAreRefused) {
  const auto error_of = [](const std::vector<std::pair<std::string, double>>& set) {
    Profile p = parsed(kSpanProfile);
    Options o;
    for (const auto& [k, v] : set) o.set(k, v);
    std::string error;
    EXPECT_FALSE(apply_options(p, o, error));
    return error;
  };
  EXPECT_EQ(error_of({{"max_frequency_hz", 10}}),
            "profile span-drive: speed_rpm's rpm_factor '(max_frequency_hz - min_frequency_hz) "
            "* 120 / motor_poles / 10000' is 0 with max_frequency_hz = 10, min_frequency_hz = 10, "
            "motor_poles = 4: a factor must be above 0 (the device's options)");
  EXPECT_THAT(error_of({{"min_frequency_hz", 60}}),
              HasSubstr("is -0.03 with max_frequency_hz = 50, min_frequency_hz = 60"));
  Profile p = parsed(kSpanProfile);
  Options o;
  o.set("min_frequency_hz", 49.0);
  std::string error;
  EXPECT_TRUE(apply_options(p, o, error)) << error;
}

// The golden values worked by hand (kSpanProfile's comment): the frames the driver sends.
TEST(RpmOffset, TheSetpointIsWrittenAsRpmLessTheOffsetOverTheFactor) {
  const TimePoint now = TimePoint{} + 10s;
  const auto frame_for = [](std::int32_t rpm) {
    return setpoint_frame(driver_of(parsed(kSpanProfile)), rpm);
  };
  EXPECT_EQ(frame_for(900), fc06(1, 5000));    // 30 Hz
  EXPECT_EQ(frame_for(300), fc06(1, 0));       // 10 Hz, the minimum
  EXPECT_EQ(frame_for(1500), fc06(1, 10000));  // 50 Hz, the maximum
  EXPECT_EQ(frame_for(1000), fc06(1, 5833));   // 700 / 0.12 = 5833.3, rounded
  // Below the minimum frequency or above the maximum: exception 03, nothing sent.
  for (const std::int32_t rpm : {200, 299, 1501, 0, -900}) {
    ModbusDriver d = driver_of(parsed(kSpanProfile));
    const WriteOp op = WriteOp::of_setpoint(rpm);
    EXPECT_EQ(d.check(std::span(&op, 1)), WriteCheck::invalid_value) << rpm;
    EXPECT_EQ(d.apply(op, 1, now), WriteStatus::invalid_value) << rpm;
    EXPECT_EQ(d.next_exchange(now)->frame[1], 0x03) << rpm;  // a poll, not a write
  }
  // 2 poles, 5..60 Hz (60 rpm a Hz): 3600 rpm is 60 Hz, raw 10000; 300 rpm is 5 Hz, raw 0;
  // 1000 rpm is (1000 - 300) / 0.33 = 2121.2, raw 2121.
  const Profile two =
      with_options(parsed(kSpanProfile),
                   {{"motor_poles", 2}, {"min_frequency_hz", 5}, {"max_frequency_hz", 60}});
  for (const auto& [rpm, raw] : std::initializer_list<std::pair<std::int32_t, std::uint16_t>>{
           {3600, 10000}, {300, 0}, {1000, 2121}}) {
    EXPECT_EQ(setpoint_frame(driver_of(two), rpm), fc06(1, raw)) << rpm;
  }
}

TEST(RpmOffset, TheSpeedReadsAsTheValueTimesTheFactorPlusTheOffset) {
  const TimePoint now = TimePoint{} + 10s;
  const auto read = [&](std::uint16_t reference, std::uint16_t actual) {
    ModbusDriver d = driver_of(parsed(kSpanProfile));
    EXPECT_TRUE(d.next_exchange(now));
    std::vector<std::uint8_t> pdu = {0x03, 8};
    for (const std::uint16_t w :
         std::initializer_list<std::uint16_t>{0x0001, reference, 0x0002, actual})
      put_be16(pdu, w);
    EXPECT_EQ(d.on_receive(frame(pdu), now).kind, RxKind::reply);
    return std::pair(d.common().speed_rpm, d.common().setpoint_rpm);
  };
  // Actual raw 5000 = 900 rpm; the reference adopted through its own factor and offset.
  EXPECT_EQ(read(5000, 5000), std::pair(900, 900));
  EXPECT_EQ(read(0, 0), std::pair(300, 300));
  EXPECT_EQ(read(10000, 10000), std::pair(1500, 1500));
  EXPECT_EQ(read(10000, 4999), std::pair(900, 1500));  // 899.88 rounded
}

// --- sequence ---

// The hz drive's driver, driven by hand through its command sequences: every value goes to the
// control word (holding 0) by FC 06.
class Sequence : public DriverAtHand {
 protected:
  Sequence() : DriverAtHand(kSlave, parsed(kHzProfile)) {}

  // `c` applied as write `ticket`: pending.
  void apply(Command c, Ticket ticket = 1) {
    EXPECT_EQ(d.apply(WriteOp::of_command(c), ticket, now), WriteStatus::pending);
  }
  // The slave echoes the write of `value`: it took it.
  void echo(std::uint16_t value) { EXPECT_EQ(d.on_receive(fc06(0, value), now).kind, RxKind::ack); }
  // The driver sends each of `values` in turn, and the slave echoes each.
  void confirmed(std::initializer_list<std::uint16_t> values) {
    for (const std::uint16_t v : values) {
      ASSERT_EQ(sent(), fc06(0, v));
      echo(v);
    }
  }
};

TEST_F(Sequence, IsReadAndItsLastValueIsTheCommand) {
  const Profile p = parsed(kHzProfile);
  ASSERT_TRUE(p.common.run_forward);
  EXPECT_THAT(p.common.run_forward->sequence, ElementsAre(0x0006, 0x0007, 0x000F));
  EXPECT_EQ(p.common.run_forward->value, 0x000F);
  // The run's sequence written as `sequence`.
  const auto run_forward = [](const std::string& sequence) {
    return errors_of(hz_with("sequence = [0x0006, 0x0007, 0x000F]", sequence));
  };
  expect_refused(run_forward,
                 {{"sequence = []", {"common.run_forward.sequence: must be 1..4 values"}},
                  {"sequence = [1,2,3,4,5]", {"must be 1..4 values"}},
                  {"sequence = [1, 70000]", {"must be 1..4 values"}},
                  {"sequence = [1], value = 1", {"value or sequence, not both"}}});
}

// Each value is written and confirmed before the next; the command is answered with the last.
TEST_F(Sequence, EachValueIsConfirmedBeforeTheNextAndTheLastAnswersTheCommand) {
  apply(Command::run_forward);
  for (const std::uint16_t v : std::initializer_list<std::uint16_t>{0x0006, 0x0007}) {
    confirmed({v});
    EXPECT_TRUE(completions(d).empty());
    EXPECT_EQ(d.common().command, Command::stop);
  }
  confirmed({0x000F});
  EXPECT_THAT(completions(d), ElementsAre(std::pair<Ticket, WriteResult>(1, WriteResult::ok)));
  EXPECT_EQ(d.common().command, Command::run_forward);
}

TEST_F(Sequence, ARefusalMidSequenceRefusesTheCommandAndSendsNoMore) {
  apply(Command::run_forward);
  confirmed({0x0006});
  ASSERT_EQ(sent(), fc06(0, 0x0007));
  d.on_receive(frame({0x86, 0x04}), now);  // exception 04, slave device failure
  EXPECT_THAT(completions(d), ElementsAre(std::pair<Ticket, WriteResult>(1, WriteResult::refused)));
  EXPECT_EQ(d.common().command, Command::stop);
  // What comes next is a poll, never the third value.
  EXPECT_EQ(sent()[1], 0x03);
}

TEST_F(Sequence, NoAnswerMidSequenceIsNoResponseAndSendsNoMore) {
  apply(Command::run_reverse);
  confirmed({0x0006});
  ASSERT_EQ(sent(), fc06(0, 0x080F));
  d.on_no_reply(now);
  EXPECT_THAT(completions(d),
              ElementsAre(std::pair<Ticket, WriteResult>(1, WriteResult::no_response)));
  EXPECT_EQ(sent()[1], 0x03);
}

// The line lost mid-sequence (comm_lost): the command fails, and once the slave answers again
// nothing of it is sent: the drive stays at the step it confirmed.
TEST_F(Sequence, TheLineLostMidSequenceFailsItAndSendsNoMore) {
  apply(Command::run_forward);
  confirmed({0x0006});
  ASSERT_EQ(sent(), fc06(0, 0x0007));
  now += 3s;
  d.on_comm_lost(now);
  EXPECT_THAT(completions(d),
              ElementsAre(std::pair<Ticket, WriteResult>(1, WriteResult::no_response)));
  int polls = 0;
  for (int i = 0; i < 10; ++i) {
    if (const auto ex = d.next_exchange(now)) {
      EXPECT_NE(ex->frame[1], 0x06);  // polls only
      ++polls;
      d.on_no_reply(now);
    }
    now += 500ms;
  }
  EXPECT_GT(polls, 0);
  EXPECT_EQ(d.common().command, Command::stop);
}

// A stop applied while a run's sequence is on the line: the run ends at the step it reached and
// is not carried out; the stop's sequence goes next, whole.
TEST_F(Sequence, AStopDuringARunSequenceOvertakesIt) {
  apply(Command::run_forward);
  ASSERT_EQ(sent(), fc06(0, 0x0006));
  apply(Command::stop, 2);
  echo(0x0006);
  EXPECT_THAT(completions(d),
              ElementsAre(std::pair<Ticket, WriteResult>(1, WriteResult::no_response)));
  confirmed({0x0007, 0x0006});
  EXPECT_THAT(completions(d), ElementsAre(std::pair<Ticket, WriteResult>(2, WriteResult::ok)));
  EXPECT_EQ(d.common().command, Command::stop);
}

// --- on the bus engine, against the profile's simulator ---

TEST(ProfileOptionsOnTheBus, TheSchemaHasTheProfilesOptionsAndTheDeviceItsValues) {
  const ProfileFile f(kHzProfile, "hz.toml");
  const AdapterDescriptor& a = specialised_for(f.path);
  std::string error;
  Options o = default_options(a);
  EXPECT_FALSE(set_option_text(a, o, "motor_poles", "60", error));
  EXPECT_THAT(error, HasSubstr("2..48"));
  EXPECT_FALSE(set_option_text(a, o, "motor_poles", "nan", error));
  EXPECT_FALSE(set_option_text(a, o, "poles", "2", error));
  test::BusRig rig(a);
  Device& d = rig.add_device("d", kSlave, {{"profile", f.path}, {"motor_poles", "2"}});
  rig.add_simulator(kSlave, {{"profile", f.path}, {"motor_poles", "2"}});
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return d.online(); }, 3s));
  // The common block: command, setpoint (registers 0 and 1 of the register map).
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, 0, {1, 1500}), Outcome::ok);
  EXPECT_TRUE(rig.run_until([&] { return rig.value(d, "speed_rpm") == 1500; }, 3s));
  // 1500 rpm at 2 poles is 25.00 Hz: the slave holds 2500 and ran the whole sequence.
  const std::string state = rig.simulator().control("state", rig.now());
  EXPECT_THAT(state, HasSubstr("frequency_reference = 25"));
  EXPECT_THAT(state, HasSubstr("running forward"));
  EXPECT_THAT(state, HasSubstr("control_word = 15"));
  // 32767 rpm is 546 Hz at 2 poles, beyond the reference's 400 Hz: exception 03, nothing sent.
  const std::size_t before = rig.sent().size();
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, 1, {32767}), Outcome::invalid_value);
  for (std::size_t i = before; i < rig.sent().size(); ++i) EXPECT_NE(rig.sent()[i].bytes[1], 0x06);
}

// The failsafe stops through the stop sequence: both values on the wire, in order.
TEST(ProfileOptionsOnTheBus, TheFailsafeStopIsTheStopSequence) {
  const ProfileFile f(kHzProfile, "hz.toml");
  const AdapterDescriptor& a = specialised_for(f.path);
  test::BusRig rig(a);
  DeviceConfig c = rig.device_config("d", kSlave, {{"profile", f.path}});
  c.failsafe.timeout = 500ms;
  c.failsafe.action = FailsafeAction::stop;
  Device& d = rig.add_device(c);
  rig.add_simulator(kSlave, {{"profile", f.path}});
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return d.online(); }, 3s));
  ASSERT_EQ(rig.write_and_wait(d, Table::holding, 0, {1, 1500}), Outcome::ok);
  const std::size_t mark = rig.sent().size();
  ASSERT_TRUE(rig.run_until(
      [&] {
        return rig.simulator().control("state", rig.now()).find("stopped") != std::string::npos;
      },
      3s));
  std::vector<Bytes> writes;
  for (std::size_t i = mark; i < rig.sent().size(); ++i) {
    if (rig.sent()[i].bytes[1] == 0x06) writes.push_back(rig.sent()[i].bytes);
  }
  EXPECT_THAT(writes, ElementsAre(fc06(0, 0x0007), fc06(0, 0x0006)));
}

// On the bus engine against the simulator: the PLC writes 900 rpm and run, and the wire carries
// raw 5000; the simulated drive runs at it and the speed reads 900; 200 rpm is refused with
// nothing on the wire.
TEST(RpmOffset, OnTheBusTheSetpointReachesTheWireAsTheSpansRaw) {
  const ProfileFile f(kSpanProfile, "hz.toml");
  const AdapterDescriptor& a = specialised_for(f.path);
  test::BusRig rig(a);
  Device& d = rig.add_device("d", kSlave, {{"profile", f.path}});
  rig.add_simulator(kSlave, {{"profile", f.path}});
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return d.online(); }, 3s));
  std::size_t mark = rig.sent().size();
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, 0, {1, 900}), Outcome::ok);
  std::vector<Bytes> writes;
  for (std::size_t i = mark; i < rig.sent().size(); ++i) {
    if (rig.sent()[i].bytes[1] != 0x03) writes.push_back(rig.sent()[i].bytes);
  }
  EXPECT_THAT(writes, testing::UnorderedElementsAre(fc06(1, 5000), fc06(0, 0x0001)));
  EXPECT_TRUE(rig.run_until([&] { return rig.value(d, "speed_rpm") == 900; }, 3s));
  EXPECT_EQ(rig.value(d, "setpoint_rpm"), 900u);
  EXPECT_THAT(rig.simulator().control("state", rig.now()),
              testing::AllOf(HasSubstr("running forward"), HasSubstr("speed_reference = 5000"),
                             HasSubstr("actual_speed = 5000")));
  // 200 rpm is below the 300 rpm of the minimum frequency: exception 03, nothing sent, the
  // reference and the setpoint unchanged.
  mark = rig.sent().size();
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, 1, {200}), Outcome::invalid_value);
  for (std::size_t i = mark; i < rig.sent().size(); ++i) EXPECT_EQ(rig.sent()[i].bytes[1], 0x03);
  EXPECT_EQ(rig.value(d, "setpoint_rpm"), 900u);
  EXPECT_THAT(rig.simulator().control("state", rig.now()), HasSubstr("speed_reference = 5000"));
}

}  // namespace
}  // namespace drivegate::modbus_device
