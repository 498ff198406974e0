// The shipped profiles of real drives against their documents (adapters/modbus/profiles/): each
// loads and is found by name; its read plan is what its document's addresses make; and the
// frames its document prints are the ones its driver sends and its simulator answers.
//
// Eaton M-Max: "M-Max Series Adjustable Frequency Drive, User Manual", MN04020003E, October 2013,
// "Serial Interface (Modbus RTU)", p.140 - 141 ("Explanation of Function Code"): its example
// frames, every CRC of which was checked (the FC 06 request prints its CRC as C2 C8, the bytes
// of its response's C8 C2 swapped; C8 C2 is the CRC of those bytes).
// ED3100 in the standard form: shared/specs/001_72ee6bb390071927.txt and shared/specs/README.md
// "ed3100 (001)"; the ED3100's own adapter is compared with it in ed3100_standard_test.cpp.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "driver.h"
#include "example_profile.h"
#include "planner.h"
#include "profile.h"
#include "profile_examples.h"
#include "profile_options.h"
#include "profile_support.h"
#include "settings.h"
#include "simulator.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;
using support::completions;
using support::read_pdu;
using support::with_options;
using support::words_pdu;
using ::testing::ElementsAre;

Profile shipped_profile(const std::string& name) {
  auto r = parse_profile(shipped::text(name), name + ".toml");
  if (auto* errors = std::get_if<std::vector<std::string>>(&r)) {
    ADD_FAILURE() << ::testing::PrintToString(*errors);
    return {};
  }
  return std::get<Profile>(std::move(r));
}

Bytes hex(std::initializer_list<std::uint8_t> bytes) {
  return Bytes(bytes);
}

// --- every shipped profile ---

TEST(ShippedProfiles, EachLoadsIsNamedAfterItsFileAndIsFoundByName) {
  std::size_t count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(DRIVEGATE_PROFILE_DIR)) {
    if (entry.path().extension() != ".toml") continue;
    ++count;
    const std::string name = entry.path().stem().string();
    SCOPED_TRACE(name);
    const Profile p = shipped_profile(name);
    EXPECT_EQ(p.name, name);
    EXPECT_FALSE(p.source.empty());
    std::string error;
    const auto found = find_profile(name, error);
    ASSERT_TRUE(found) << error;
    // Built into the plugin (embed_profiles.cmake), unless an installed copy comes first.
    if (found->source == "shipped " + name) {
      EXPECT_EQ(found->text, shipped::text(name));
    }
  }
  EXPECT_GE(count, 3u);  // example-vfd, ed3100-standard, eaton-m-max
}

// --- Eaton M-Max (MN04020003E) ---

constexpr std::uint8_t kMmxSlave = 5;  // the address of every example on p.140 - 141

// 9600 baud, no parity, 2 stop bits: 11 bits a character.
ModbusDriver mmx_driver() {
  return support::driver_at_its_line(kMmxSlave, shipped_profile("eaton-m-max"));
}

TEST(EatonMMax, TheLineAndTheReadPlanFollowTheManual) {
  const Profile p = shipped_profile("eaton-m-max");
  // p.132: S2.4 factory setting 9600 baud, S2.6 factory setting none with 2 stop bits.
  EXPECT_EQ(p.line.baud, 9600u);
  EXPECT_EQ(p.line.parity, Parity::none);
  EXPECT_EQ(p.line.stop_bits, 2);
  // Two reads: the input process data ID 2001 - 2003 (ID 2002 read through), the output process
  // data ID 2101 - 2111, each at its ID - 1 (p.136, p.140).
  const auto plan = plan_reads(p);
  ASSERT_EQ(plan.size(), 2u);
  EXPECT_EQ(plan[0].table, Table::input);
  EXPECT_EQ(plan[0].start, 2100);
  EXPECT_EQ(plan[0].count, 11);
  EXPECT_EQ(plan[1].table, Table::holding);
  EXPECT_EQ(plan[1].start, 2000);
  EXPECT_EQ(plan[1].count, 3);
  // The control word's values (p.137), one of them the p.141 example's 0003 "anticlockwise, RUN".
  const CommonBindings& c = p.common;
  ASSERT_TRUE(c.stop && c.run_forward && c.run_reverse && c.reset_fault);
  EXPECT_EQ(c.stop->value, 0x0000);
  EXPECT_EQ(c.run_forward->value, 0x0001);
  EXPECT_EQ(c.run_reverse->value, 0x0003);
  EXPECT_EQ(c.reset_fault->value, 0x0004);
  EXPECT_EQ(p.points[c.stop->point].address, 0x07D0);
  // ID 2003 is a % of the span between the minimum and the maximum frequency (p.138).
  ASSERT_TRUE(c.setpoint_rpm);
  EXPECT_EQ(p.points[*c.setpoint_rpm].address, 0x07D2);
  EXPECT_TRUE(c.setpoint_offset);
}

// ID 2003 is 0 - 10000 over the span from P6.3 to P6.4 (p.138), whose factory settings are
// 0.00 and 60.00 Hz (p.83): at 4 poles 1800 rpm is 60 Hz, the 2710 hex (100.00 %) of the p.141
// function 10 example; a device whose drive has other limits says so in its options.
TEST(EatonMMax, ItsSetpointInRpmSpansTheMinimumToTheMaximumFrequency) {
  const TimePoint now = TimePoint{} + 10s;
  const auto fc06 = [](std::uint16_t raw) {
    return encode(Framing::rtu, kMmxSlave,
                  std::vector<std::uint8_t>{0x06, 0x07, 0xD2, static_cast<std::uint8_t>(raw >> 8),
                                            static_cast<std::uint8_t>(raw & 0xFF)});
  };
  const auto driver_with = [](std::vector<std::pair<std::string, double>> set) {
    set.insert(set.begin(), {"motor_poles", 4.0});  // required: the motor's nameplate
    return support::driver_at_its_line(kMmxSlave,
                                       with_options(shipped_profile("eaton-m-max"), set));
  };
  const auto frame_for = [&](ModbusDriver d, std::int32_t rpm) {
    EXPECT_EQ(d.apply(WriteOp::of_setpoint(rpm), 1, now), WriteStatus::pending) << rpm;
    return d.next_exchange(now)->frame;
  };
  const auto refused = [&](ModbusDriver d, std::int32_t rpm) {
    const WriteOp op = WriteOp::of_setpoint(rpm);
    EXPECT_EQ(d.apply(op, 1, now), WriteStatus::invalid_value) << rpm;
    return d.next_exchange(now)->frame[1] != 0x06;  // a poll follows, not a write
  };
  // The factory span 0 - 60 Hz.
  EXPECT_EQ(frame_for(driver_with({}), 1800), fc06(10000));
  EXPECT_EQ(frame_for(driver_with({}), 1800),
            hex({0x05, 0x06, 0x07, 0xD2, 0x27, 0x10, 0x33, 0x3F}));
  EXPECT_EQ(frame_for(driver_with({}), 900), fc06(5000));
  EXPECT_EQ(frame_for(driver_with({}), 0), fc06(0));
  EXPECT_TRUE(refused(driver_with({}), 1801));
  // A drive set to 10 - 50 Hz: 300 rpm is the minimum (raw 0), 900 rpm is half the span.
  const std::vector<std::pair<std::string, double>> span = {{"min_frequency_hz", 10},
                                                            {"max_frequency_hz", 50}};
  EXPECT_EQ(frame_for(driver_with(span), 300), fc06(0));
  EXPECT_EQ(frame_for(driver_with(span), 900), fc06(5000));
  EXPECT_EQ(frame_for(driver_with(span), 1500), fc06(10000));
  EXPECT_TRUE(refused(driver_with(span), 200));
  EXPECT_TRUE(refused(driver_with(span), 1501));
}

TEST(EatonMMax, TheManualsReadsAddressTheProfilesSpeedAndCurrent) {
  const Profile p = shipped_profile("eaton-m-max");
  const ProfilePoint& speed = p.points[*p.find("motor_speed")];
  const ProfilePoint& current = p.points[*p.find("motor_current")];
  EXPECT_EQ(current.address, speed.address + 1);
  // p.140, "Function Code 03": master request 05 03 0838 0002 4622; "Function Code 04": the
  // same registers as input registers, 05 04 0838 0002 F3E2.
  EXPECT_EQ(encode(Framing::rtu, kMmxSlave, read_pdu(0x03, speed.address, 2)),
            hex({0x05, 0x03, 0x08, 0x38, 0x00, 0x02, 0x46, 0x22}));
  EXPECT_EQ(encode(Framing::rtu, kMmxSlave, read_pdu(0x04, speed.address, 2)),
            hex({0x05, 0x04, 0x08, 0x38, 0x00, 0x02, 0xF3, 0xE2}));
}

TEST(EatonMMax, ItsSimulatorAnswersTheManualsFunction04ExampleWithTheManualsReply) {
  ModbusSimulator sim(kMmxSlave, shipped_profile("eaton-m-max"));
  // p.140: motor speed 1495 rpm (05D7), motor current 0.24 A (0018).
  ASSERT_EQ(sim.control("set motor_speed 1495", TimePoint{}).rfind("ok", 0), 0u);
  ASSERT_EQ(sim.control("set motor_current 0.24", TimePoint{}).rfind("ok", 0), 0u);
  EXPECT_EQ(sim.on_receive(hex({0x05, 0x04, 0x08, 0x38, 0x00, 0x02, 0xF3, 0xE2}), TimePoint{}),
            hex({0x05, 0x04, 0x04, 0x05, 0xD7, 0x00, 0x18, 0x0E, 0xBA}));
}

TEST(EatonMMax, ItsSimulatorTakesTheManualsFunction10Example) {
  ModbusSimulator sim(kMmxSlave, shipped_profile("eaton-m-max"));
  // p.141: control word 0001 (run, FWD), general control word 0000, speed setpoint 2710 hex
  // (10000 = 100.00 %), and the reply 05 10 07D0 0003 8101.
  EXPECT_EQ(sim.on_receive(hex({0x05, 0x10, 0x07, 0xD0, 0x00, 0x03, 0x06, 0x00, 0x01, 0x00, 0x00,
                                0x27, 0x10, 0xD1, 0x25}),
                           TimePoint{}),
            hex({0x05, 0x10, 0x07, 0xD0, 0x00, 0x03, 0x81, 0x01}));
  const std::string state = sim.control("state", TimePoint{});
  EXPECT_NE(state.find("running forward"), std::string::npos) << state;
  EXPECT_NE(state.find("speed_setpoint = 100"), std::string::npos) << state;
}

// The manual's frames are the profile's [[example]]s: the profile agrees with each
// (profile_examples.h), and its simulator answers each request with the manual's reply.
TEST(EatonMMax, ItsExamplesAreTheManualsFramesAndItsSimulatorAnswersThem) {
  const Profile p = shipped_profile("eaton-m-max");
  ASSERT_EQ(p.examples.size(), 3u);  // p.140 FC 04, p.141 FC 06 and FC 10
  EXPECT_TRUE(check_examples(p, "eaton-m-max.toml").empty())
      << ::testing::PrintToString(check_examples(p, "eaton-m-max.toml"));
  ModbusSimulator sim(kMmxSlave, shipped_profile("eaton-m-max"));
  ASSERT_EQ(sim.control("set motor_speed 1495", TimePoint{}).rfind("ok", 0), 0u);
  ASSERT_EQ(sim.control("set motor_current 0.24", TimePoint{}).rfind("ok", 0), 0u);
  for (const ProfileExample& e : p.examples) {
    SCOPED_TRACE(e.request);
    EXPECT_EQ(sim.on_receive(*example_frame(p, e.request), TimePoint{}),
              *example_frame(p, e.reply));
  }
  // The FC 06 example is the frame the driver sends for run reverse.
  ModbusDriver d = mmx_driver();
  const TimePoint now = TimePoint{} + 10s;
  ASSERT_EQ(d.apply(WriteOp::of_command(Command::run_reverse), 1, now), WriteStatus::pending);
  EXPECT_EQ(d.next_exchange(now)->frame, *example_frame(p, p.examples[1].request));
}

TEST(EatonMMax, ItsDriverReadsTheOutputProcessDataIntoTheCommonBlock) {
  ModbusDriver d = mmx_driver();
  TimePoint now = TimePoint{} + 10s;
  auto sent = [&] {
    const auto ex = d.next_exchange(now);
    return ex ? ex->frame : Bytes{};
  };
  // ID 2101 - 2111: READY and RUN, FWD; 49.83 Hz; 1495 rpm; 0.24 A (p.140's values); no error.
  ASSERT_EQ(sent(), encode(Framing::rtu, kMmxSlave, read_pdu(0x04, 2100, 11)));
  EXPECT_EQ(
      d.on_receive(
           encode(Framing::rtu, kMmxSlave,
                  words_pdu(0x04, {0x0003, 0x0003, 9966, 4983, 1495, 24, 512, 498, 2300, 540, 0})),
           now)
          .kind,
      RxKind::reply);
  ASSERT_EQ(sent(), encode(Framing::rtu, kMmxSlave, read_pdu(0x03, 2000, 3)));
  EXPECT_EQ(
      d.on_receive(encode(Framing::rtu, kMmxSlave, words_pdu(0x03, {0x0001, 0, 10000})), now).kind,
      RxKind::reply);
  EXPECT_TRUE(d.common().ready);
  EXPECT_TRUE(d.common().running);
  EXPECT_EQ(d.common().speed_rpm, 1495);
  EXPECT_TRUE(d.common().faults.empty());
  const auto value = [&](std::string_view name) {
    for (std::size_t i = 0; i < d.points().size(); ++i) {
      if (d.points()[i].name == name) return as_double(d.values()[i]);
    }
    ADD_FAILURE() << "no point " << name;
    return 0.0;
  };
  EXPECT_DOUBLE_EQ(value("motor_current"), 0.24);
  EXPECT_DOUBLE_EQ(value("motor_frequency"), 49.83);
  // ID 2003 = 10000 (100.00 %) is the factory maximum frequency, 60 Hz (p.83): 1800 rpm at 4 poles.
  EXPECT_EQ(d.common().setpoint_rpm, 1800);
  // A trip: status bit 3 (FAULT), RUN clear; the error code stays raw (the list is not mapped).
  now += 500ms;
  ASSERT_EQ(sent(), encode(Framing::rtu, kMmxSlave, read_pdu(0x04, 2100, 11)));
  d.on_receive(encode(Framing::rtu, kMmxSlave,
                      words_pdu(0x04, {0x0009, 0x0003, 0, 0, 0, 0, 0, 0, 0, 540, 9})),
               now);
  ASSERT_EQ(sent(), encode(Framing::rtu, kMmxSlave, read_pdu(0x03, 2000, 3)));
  d.on_receive(encode(Framing::rtu, kMmxSlave, words_pdu(0x03, {0x0001, 0, 10000})), now);
  EXPECT_FALSE(d.common().running);
  EXPECT_TRUE(d.common().faults.has(Fault::other));
  EXPECT_EQ(d.common().native_fault, 9u);
}

TEST(EatonMMax, RunReverseIsTheManualsFunction06Example) {
  ModbusDriver d = mmx_driver();
  const TimePoint now = TimePoint{} + 10s;
  const WriteOp reverse = WriteOp::of_command(Command::run_reverse);
  ASSERT_EQ(d.check(std::span(&reverse, 1)), WriteCheck::ok);
  ASSERT_EQ(d.apply(reverse, 1, now), WriteStatus::pending);
  // p.141: 05 06 07D0 0003, "anticlockwise, RUN". The CRC is C8 C2 (printed so for the
  // response; the request's C2 C8 has its bytes swapped).
  const Bytes manual = hex({0x05, 0x06, 0x07, 0xD0, 0x00, 0x03, 0xC8, 0xC2});
  const auto ex = d.next_exchange(now);
  ASSERT_TRUE(ex);
  EXPECT_EQ(ex->frame, manual);
  // "The slave response is a copy of the master request if it is a normal response."
  EXPECT_EQ(d.on_receive(manual, now).kind, RxKind::ack);
  EXPECT_THAT(completions(d), ElementsAre(std::pair<Ticket, WriteResult>(1, WriteResult::ok)));
  EXPECT_EQ(d.common().command, Command::run_reverse);
  // The simulator of the profile answers it with the same copy.
  ModbusSimulator sim(kMmxSlave, shipped_profile("eaton-m-max"));
  EXPECT_EQ(sim.on_receive(manual, TimePoint{}), manual);
}

TEST(EatonMMax, StopAndResetAreTheControlWordsBits) {
  ModbusDriver d = mmx_driver();
  const TimePoint now = TimePoint{} + 10s;
  const WriteOp stop = WriteOp::of_command(Command::stop);
  ASSERT_EQ(d.apply(stop, 1, now), WriteStatus::pending);
  EXPECT_EQ(
      d.next_exchange(now)->frame,
      encode(Framing::rtu, kMmxSlave, std::vector<std::uint8_t>{0x06, 0x07, 0xD0, 0x00, 0x00}));
  d.on_no_reply(now);
  const WriteOp reset = WriteOp::of_command(Command::reset_fault);
  ASSERT_EQ(d.apply(reset, 2, now), WriteStatus::pending);
  EXPECT_EQ(
      d.next_exchange(now)->frame,
      encode(Framing::rtu, kMmxSlave, std::vector<std::uint8_t>{0x06, 0x07, 0xD0, 0x00, 0x04}));
  // The rpm setpoint is ID 2003 within P6.3 - P6.4: 1500 rpm (50 Hz) is in the factory span of
  // 0 - 60 Hz, 1900 rpm (63.3 Hz) beyond it.
  const WriteOp setpoint = WriteOp::of_setpoint(1500);
  EXPECT_EQ(d.check(std::span(&setpoint, 1)), WriteCheck::ok);
  const WriteOp beyond = WriteOp::of_setpoint(1900);
  EXPECT_EQ(d.check(std::span(&beyond, 1)), WriteCheck::invalid_value);
}

// --- Vacon 100 (DPD00156C and its FBFixed appendix) ---

// FB Speed Reference 2003 (wire 2002) is 0..10000 of the span from the minimum to the maximum
// frequency (appendix 8.4.10): with the drive's minimum at 10 Hz, 300 rpm (10 Hz at 4 poles) is
// raw 0 and 900 rpm raw 5000, not the 3000 a span starting at 0 Hz would give.
TEST(Vacon100, ItsSetpointInRpmSpansTheMinimumToTheMaximumFrequency) {
  constexpr std::uint8_t kSlave = 1;
  const TimePoint now = TimePoint{} + 10s;
  const auto frame_for = [&](const std::vector<std::pair<std::string, double>>& set,
                             std::int32_t rpm) {
    auto all = set;
    all.insert(all.begin(), {"motor_poles", 4.0});  // required: the motor's nameplate
    ModbusDriver d =
        support::driver_at_its_line(kSlave, with_options(shipped_profile("vacon-100"), all));
    const WriteOp op = WriteOp::of_setpoint(rpm);
    EXPECT_EQ(d.apply(op, 1, now), WriteStatus::pending) << rpm;
    return d.next_exchange(now)->frame;
  };
  const auto fc06 = [](std::uint16_t raw) {
    return encode(Framing::rtu, kSlave,
                  std::vector<std::uint8_t>{0x06, 0x07, 0xD2, static_cast<std::uint8_t>(raw >> 8),
                                            static_cast<std::uint8_t>(raw & 0xFF)});
  };
  const std::vector<std::pair<std::string, double>> span = {{"min_frequency_hz", 10},
                                                            {"max_frequency_hz", 50}};
  EXPECT_EQ(frame_for(span, 300), fc06(0));
  EXPECT_EQ(frame_for(span, 900), fc06(5000));
  EXPECT_EQ(frame_for(span, 900), hex({0x01, 0x06, 0x07, 0xD2, 0x13, 0x88, 0x25, 0xD1}));
  EXPECT_EQ(frame_for(span, 1500), fc06(10000));
  // A drive set to 0 - 50 Hz: 1500 rpm is the whole span.
  const std::vector<std::pair<std::string, double>> from_0 = {{"min_frequency_hz", 0},
                                                              {"max_frequency_hz", 50}};
  EXPECT_EQ(frame_for(from_0, 1500), fc06(10000));
  EXPECT_EQ(frame_for(from_0, 750), fc06(5000));
  // Neither factory value is cited: a device that leaves either out is refused, naming it.
  Profile p = shipped_profile("vacon-100");
  Options o;
  o.set("motor_poles", 4.0);
  o.set("min_frequency_hz", 0.0);
  std::string error;
  EXPECT_FALSE(apply_options(p, o, error));
  EXPECT_THAT(error, testing::StartsWith("option max_frequency_hz is required and not set: the "
                                         "drive's maximum frequency"));
}

// --- Eaton PowerXL DG1 (MN040010EN) ---

// ID 2003 (wire 2002) is 0..10000 over P1.1 Minimum .. P1.2 Maximum Frequency ([MN2018] p.28),
// whose factory settings were not read: a device sets both, and the poles. At P1.1 = 10 Hz and
// P1.2 = 50 Hz, 4 poles: 300 rpm is raw 0, 900 rpm (30 Hz) raw 5000, 1500 rpm raw 10000; 1501
// rpm is refused with nothing sent. Left out, each is refused by name.
TEST(EatonDg1, ItsSetpointInRpmSpansP11ToP12AndTheyAreRequired) {
  constexpr std::uint8_t kSlave = 1;
  const TimePoint now = TimePoint{} + 10s;
  const std::vector<std::pair<std::string, double>> span = {
      {"min_frequency_hz", 10}, {"max_frequency_hz", 50}, {"motor_poles", 4}};
  const auto driver_with = [](const std::vector<std::pair<std::string, double>>& set) {
    return support::driver_at_its_line(kSlave, with_options(shipped_profile("eaton-dg1"), set));
  };
  const auto fc06 = [](std::uint16_t raw) {
    return encode(Framing::rtu, kSlave,
                  std::vector<std::uint8_t>{0x06, 0x07, 0xD2, static_cast<std::uint8_t>(raw >> 8),
                                            static_cast<std::uint8_t>(raw & 0xFF)});
  };
  const auto frame_for = [&](std::int32_t rpm) {
    ModbusDriver d = driver_with(span);
    EXPECT_EQ(d.apply(WriteOp::of_setpoint(rpm), 1, now), WriteStatus::pending) << rpm;
    return d.next_exchange(now)->frame;
  };
  EXPECT_EQ(frame_for(300), fc06(0));
  EXPECT_EQ(frame_for(900), fc06(5000));
  EXPECT_EQ(frame_for(1500), fc06(10000));
  ModbusDriver d = driver_with(span);
  EXPECT_EQ(d.apply(WriteOp::of_setpoint(1501), 1, now), WriteStatus::invalid_value);
  EXPECT_NE(d.next_exchange(now)->frame[1], 0x06);  // a poll follows, not a write
  for (std::size_t left_out = 0; left_out < span.size(); ++left_out) {
    Profile p = shipped_profile("eaton-dg1");
    Options o;
    for (std::size_t i = 0; i < span.size(); ++i) {
      if (i != left_out) o.set(span[i].first, span[i].second);
    }
    std::string error;
    EXPECT_FALSE(apply_options(p, o, error));
    EXPECT_THAT(error, testing::StartsWith("option " + span[left_out].first +
                                           " is required and not set: "));
  }
}

// --- ED3100 answering in the standard form ---

constexpr std::uint8_t kEd3100 = 0x1F;  // the document's examples' address

TEST(Ed3100Standard, TheProfileReadsThreeTwoWordBlocks) {
  const Profile p = shipped_profile("ed3100-standard");
  // The dedicated adapter's line (adapters/ed3100/README.md, "Choices" 1): 9600 8E1.
  EXPECT_EQ(p.line.baud, 9600u);
  EXPECT_EQ(p.line.parity, Parity::even);
  EXPECT_EQ(p.line.stop_bits, 1);
  // Document "communication material structure": two data words at most a frame.
  EXPECT_EQ(p.modbus.max_registers, 2);
  const auto plan = plan_reads(p);
  ASSERT_EQ(plan.size(), 3u);
  EXPECT_EQ(plan[0], (Block{Table::holding,
                            0x0D00,
                            2,
                            {*p.find("output_frequency"), *p.find("output_frequency_format")}}));
  EXPECT_EQ(
      plan[1],
      (Block{Table::holding, 0x0E01, 2, {*p.find("drive_fault_code"), *p.find("state_word")}}));
  EXPECT_EQ(
      plan[2],
      (Block{Table::holding, 0x2000, 2, {*p.find("command"), *p.find("frequency_reference")}}));
  // specs README: 0x2000 = 0x001E forward continuous, 0x002E reverse continuous, 0x0001 stop;
  // the document has no fault reset.
  const CommonBindings& c = p.common;
  EXPECT_EQ(c.run_forward->value, 0x001E);
  EXPECT_EQ(c.run_reverse->value, 0x002E);
  EXPECT_EQ(c.stop->value, 0x0001);
  EXPECT_FALSE(c.reset_fault);
}

TEST(Ed3100Standard, TheDocumentsMonitorExampleInTheStandardFormIs42_28Hz) {
  ModbusDriver d = support::driver_at_its_line(kEd3100, shipped_profile("ed3100-standard"));
  const TimePoint now = TimePoint{} + 10s;
  ASSERT_EQ(d.next_exchange(now)->frame, encode(Framing::rtu, kEd3100, read_pdu(0x03, 0x0D00, 2)));
  // The document's monitor reply 1F 03 0D 00 10 84 41 48 47 D5, in the standard form
  // (adapters/ed3100/README.md, "Golden vectors": 1F 03 04 10 84 41 48 70 BD): 42.28 Hz with
  // format 0x4148 (two decimals, Hz, normal, stopped) = 1268 rpm at 4 poles. Stopped, this is
  // the reference on display: the profile cannot tell (ed3100-standard.toml).
  EXPECT_EQ(d.on_receive(hex({0x1F, 0x03, 0x04, 0x10, 0x84, 0x41, 0x48, 0x70, 0xBD}), now).kind,
            RxKind::reply);
  // The cycle's other blocks (fault code and state word; command and reference), a drive with no
  // fault, stopped: the cycle is published with its last.
  ASSERT_EQ(d.next_exchange(now)->frame, encode(Framing::rtu, kEd3100, read_pdu(0x03, 0x0E01, 2)));
  d.on_receive(encode(Framing::rtu, kEd3100, words_pdu(0x03, {0, 0})), now);
  ASSERT_EQ(d.next_exchange(now)->frame, encode(Framing::rtu, kEd3100, read_pdu(0x03, 0x2000, 2)));
  d.on_receive(encode(Framing::rtu, kEd3100, words_pdu(0x03, {0x0001, 0})), now);
  EXPECT_EQ(d.common().speed_rpm, 1268);
  ASSERT_EQ(d.points()[0].name, "output_frequency_format");
  EXPECT_EQ(std::get<std::int64_t>(d.values()[0]), 0x4148);
}

TEST(Ed3100Standard, TheDocumentsOwnFormIsNoReplyToTheProfile) {
  ModbusDriver d = support::driver_at_its_line(kEd3100, shipped_profile("ed3100-standard"));
  const TimePoint now = TimePoint{} + 10s;
  ASSERT_TRUE(d.next_exchange(now));
  // The document's own reply (register echoed where the byte count belongs): a standard master
  // reads 0D as a byte count and waits for bytes that never come, so the drive must be set to
  // answer in the standard form.
  EXPECT_NE(
      d.on_receive(hex({0x1F, 0x03, 0x0D, 0x00, 0x10, 0x84, 0x41, 0x48, 0x47, 0xD5}), now).kind,
      RxKind::reply);
  EXPECT_FALSE(d.common().ready);
}

TEST(Ed3100Standard, AStopIsTheDocumentsStopFrame) {
  ModbusDriver d = support::driver_at_its_line(kEd3100, shipped_profile("ed3100-standard"));
  const TimePoint now = TimePoint{} + 10s;
  const WriteOp stop = WriteOp::of_command(Command::stop);
  ASSERT_EQ(d.apply(stop, 1, now), WriteStatus::pending);
  // Document, "Written stop order": 1F 06 20 00 00 01 40 74, answered with itself.
  const Bytes document = hex({0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74});
  EXPECT_EQ(d.next_exchange(now)->frame, document);
  EXPECT_EQ(d.on_receive(document, now).kind, RxKind::ack);
  EXPECT_THAT(completions(d), ElementsAre(std::pair<Ticket, WriteResult>(1, WriteResult::ok)));
  // No fault reset in the document: refused before the line (0x03 at the PLC).
  const WriteOp reset = WriteOp::of_command(Command::reset_fault);
  EXPECT_EQ(d.check(std::span(&reset, 1)), WriteCheck::invalid_value);
}

}  // namespace
}  // namespace drivegate::modbus_device
