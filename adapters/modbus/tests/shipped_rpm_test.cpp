// The speed and the setpoint in rpm of shipped profiles whose units come from their manuals' own
// examples and tables: the frame a setpoint in rpm puts on the line is the manual's frame, and the
// speed a PLC reads is the manual's value through the profile's rpm_factor at its default (or a
// required option's example) options, or at the options a test gives the device.
//
// ENC EDS300 user manual: 7.7.3 p.42 (50 Hz = 1388H at 2001H), Appendix A Table A-4 p.48 (the
// output frequency monitor in 0.01 Hz). NORD BU 0050 GB-3111: 1.6.3 p.46 (a 50 % setpoint is
// 2000 hex), 1.5.3.7 p.36 (actual value 1 = actual frequency, 16384 = 100 %); BU 0050 DE-3111
// p.32 (100 % = maximum frequency P105). Yaskawa V1000 Technical Manual SIEP C710606 16C, C.9
// p.417 (60.00 Hz written as 1770H). Hitachi SJ series P1 User's Guide 14.4.8 p.14-18 (FA-01 and
// dA-01 at 50.00 Hz = 0000 1388h, register address = register number - 1). Inovance MD500 Series
// General-Purpose AC Drive User Manual p.110 (1000H = 2710H is 100.00 % of F0-10, 50 Hz with
// F0-10 = 50 Hz: the frame 01 06 10 00 27 10 97 36). Danfoss VLT Micro Drive FC 51 Design Guide
// MG02K202 8.11.3 p.88 (16384 = 100 %, 0 % = 3-02 and 100 % = 3-03 with 3-00 = min-max; MAV
// scaled as the reference). Eaton MN040010EN: May 2014 p.15 Startup Test (FB Speed reference
// 42002 = 5000 = 50.00 %, "The Actual value is 5000"), June 2018 pp.28, 134 (0 = minimum
// frequency P1.1, 10000 = maximum frequency P1.2, reference and actual speed).
#include <gtest/gtest.h>

#include "driver.h"
#include "example_profile.h"
#include "profile.h"
#include "profile_examples.h"
#include "profile_options.h"
#include "profile_support.h"
#include "simulator.h"

namespace drivegate::modbus_device::modbus_shipped_rpm_test {
namespace {

using namespace std::chrono_literals;

// The shipped profile `name`; a test failure, and an empty profile, if it is refused.
Profile shipped_profile(const std::string& name) {
  return support::parsed(shipped::text(name));
}

// The shipped profile `name` with a device's `options` applied (required ones included).
Profile shipped_with(const std::string& name,
                     const std::vector<std::pair<std::string, double>>& options) {
  return support::with_options(shipped_profile(name), options);
}

// The frame the driver of `p` (or of the shipped profile `name`) sends for a setpoint of `rpm`,
// or nothing when it refuses it.
std::optional<Bytes> setpoint_frame(const Profile& p, std::uint8_t slave, std::int32_t rpm) {
  return support::setpoint_frame(support::driver_at_its_line(slave, p), rpm);
}
std::optional<Bytes> setpoint_frame(const std::string& name, std::uint8_t slave, std::int32_t rpm) {
  return setpoint_frame(shipped_profile(name), slave, rpm);
}

// The speed in rpm the driver of `p` (or of the shipped profile `name`) reads once its simulator
// was told `control` (a `set POINT VALUE`), its reads answered until every read block was asked;
// `sim` is that simulator, `now` the time after the last read.
std::int32_t speed_read(const Profile& p, std::uint8_t slave, const std::string& control,
                        ModbusSimulator& sim, TimePoint& now) {
  ModbusDriver d = support::driver_at_its_line(slave, p);
  EXPECT_EQ(sim.control(control, TimePoint{}).rfind("ok", 0), 0u) << control;
  now = TimePoint{} + 10s;
  for (int i = 0; i < 32; ++i) {
    const auto ex = d.next_exchange(now);
    if (!ex) {
      now += 100ms;
      continue;
    }
    d.on_receive(sim.on_receive(ex->frame, now), now);
  }
  return d.common().speed_rpm;
}
std::int32_t speed_read(const std::string& name, std::uint8_t slave, const std::string& control) {
  const Profile p = shipped_profile(name);
  ModbusSimulator sim(slave, p);
  TimePoint now;
  return speed_read(p, slave, control, sim, now);
}

// The RTU frame of `pdu` to `slave`.
Bytes rtu(const std::vector<std::uint8_t>& pdu, std::uint8_t slave = 1) {
  return encode(Framing::rtu, slave, pdu);
}

// What a PLC and the line see of `p`'s speed at unit 1: the rpm its driver reads once the
// simulator was told `control`, and the simulator's reply to the RTU read `read_pdu` then.
struct SpeedSeen {
  std::int32_t rpm = 0;
  Bytes reply;
};
SpeedSeen speed_seen(const Profile& p, const std::string& control,
                     const std::vector<std::uint8_t>& read_pdu) {
  ModbusSimulator sim(1, p);
  TimePoint now;
  const std::int32_t rpm = speed_read(p, 1, control, sim, now);
  return {rpm, sim.on_receive(rtu(read_pdu), now)};
}

// --- ENC EDS300 ---

TEST(EncEds300Rpm, A1500RpmSetpointIsTheManuals50HzFrame) {
  // 7.7.3 "Set 1# inverter specified value to 50Hz": 01 06 20 01 13 88 DE 9C; 1500 rpm is
  // 50 Hz at the default 4 poles.
  EXPECT_EQ(setpoint_frame("enc-eds300", 1, 1500),
            Bytes({0x01, 0x06, 0x20, 0x01, 0x13, 0x88, 0xDE, 0x9C}));
}

TEST(EncEds300Rpm, TheOutputFrequencyMonitorReadsAsTheSynchronousSpeed) {
  // C-01 (1001H) at 49.50 Hz, raw 4950 in Table A-4's 0.01 Hz: 1485 rpm at 4 poles.
  EXPECT_EQ(speed_read("enc-eds300", 1, "set monitor_c01_output_frequency 49.5"), 1485);
}

// --- NORD SK 500E ---

TEST(NordSk500eRpm, A750RpmSetpointIsTheManuals50PercentSetpoint) {
  // p.46: a 50 % setpoint is 2000 hex; 100 % is P105 (DE p.32), 50 Hz by default: 25 Hz is
  // 750 rpm at 4 poles. Setpoint 1 is P050[1] (0C81H), written with FC 10H (p.66, p.67).
  EXPECT_EQ(setpoint_frame("nord-sk500e", 8, 750),
            rtu({0x10, 0x0C, 0x81, 0x00, 0x01, 0x02, 0x20, 0x00}, 8));
}

TEST(NordSk500eRpm, ActualValue1ReadsAsTheSynchronousSpeed) {
  // p.48's reply: IW1 = 2000 hex, 50 % of P105 (p.36): 25 Hz, 750 rpm at 4 poles.
  EXPECT_EQ(speed_read("nord-sk500e", 8, "set actual_value_1 50"), 750);
}

// --- Yaskawa V1000 ---

TEST(YaskawaV1000Rpm, An1800RpmSetpointWritesTheManuals1770H) {
  // p.417: 60.00 Hz is 1770H in 0002H; 1800 rpm is 60 Hz at 4 poles. FC 10H, one register.
  EXPECT_EQ(setpoint_frame("yaskawa-v1000", 1, 1800),
            rtu({0x10, 0x00, 0x02, 0x00, 0x01, 0x02, 0x17, 0x70}));
  // The manual's own frame (forward run and 60.00 Hz) is the profile's example and checks.
  const Profile p = shipped_profile("yaskawa-v1000");
  EXPECT_TRUE(check_examples(p, "yaskawa-v1000.toml").empty())
      << ::testing::PrintToString(check_examples(p, "yaskawa-v1000.toml"));
  ModbusSimulator sim(1, p);
  EXPECT_EQ(sim.on_receive(Bytes({0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x01, 0x17, 0x70,
                                  0x6D, 0xB7}),
                           TimePoint{}),
            Bytes({0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x10, 0x08}));
}

// --- Hitachi SJ-P1 ---

TEST(HitachiSjP1Rpm, A1500RpmSetpointWritesTheManuals50HzToFa01) {
  // p.14-18: 50.00 Hz is written to FA-01 as 0000 1388h at register address 2AF8h (register
  // 2AF9h - 1), two registers, high word first; 1500 rpm is 50 Hz at 4 poles. The manual's frame
  // is FC 17h; the profile writes the same two registers with FC 10h.
  EXPECT_EQ(setpoint_frame("hitachi-sj-p1", 1, 1500),
            rtu({0x10, 0x2A, 0xF8, 0x00, 0x02, 0x04, 0x00, 0x00, 0x13, 0x88}));
}

TEST(HitachiSjP1Rpm, Da01ReadsAsTheSynchronousSpeed) {
  // p.14-18's reply: dA-01 (registers 2711h/2712h) = 0000 1388h = 50.00 Hz: 1500 rpm at 4 poles;
  // the driver asks dA-01 at the register address the manual sends: 2710h, two registers.
  const SpeedSeen seen = speed_seen(shipped_profile("hitachi-sj-p1"), "set output_frequency 50",
                                    {0x03, 0x27, 0x10, 0x00, 0x02});
  EXPECT_EQ(seen.rpm, 1500);
  EXPECT_EQ(seen.reply, rtu({0x03, 0x04, 0x00, 0x00, 0x13, 0x88}));
}

// --- Inovance MD500 ---

TEST(InovanceMd500Rpm, A1500RpmSetpointIsTheManuals100PercentFrame) {
  // p.110: "Suppose that F0-10 = 50 Hz", 2710H (10000 = 100.00 %) written to 1000H is 50 Hz,
  // sent as 01 06 10 00 27 10 97 36. F0-10 is a required option; its example is that 50 Hz, and
  // 1500 rpm is 50 Hz at the example's 4 poles.
  EXPECT_EQ(setpoint_frame("inovance-md500", 1, 1500),
            Bytes({0x01, 0x06, 0x10, 0x00, 0x27, 0x10, 0x97, 0x36}));
}

TEST(InovanceMd500Rpm, TheSetpointFollowsTheMaximumFrequencyTheDeviceSets) {
  // The same 1500 rpm with F0-10 = 100 Hz (set in [device.options]) is 50.00 % of F0-10: 1388H.
  EXPECT_EQ(setpoint_frame(
                shipped_with("inovance-md500", {{"max_frequency_hz", 100.0}, {"motor_poles", 4.0}}),
                1, 1500),
            support::fc06_frame(1, 0x1000, 0x1388));
}

// --- Danfoss FC 51 ---

TEST(DanfossFc51Rpm, The100PercentReferenceIs3_03) {
  // p.88: 16384 (4000 hex) = 100 % = 3-03 Maximum Reference; at the examples (3-02 = 0 Hz,
  // 3-03 = 50 Hz, 4 poles) 1500 rpm is 50 Hz, 100 %; 750 rpm is 2000 hex. REF is register 50010,
  // address 50009 (C359h), written with FC 06.
  EXPECT_EQ(setpoint_frame("danfoss-fc51", 1, 1500), support::fc06_frame(1, 0xC359, 0x4000));
  EXPECT_EQ(setpoint_frame("danfoss-fc51", 1, 750), support::fc06_frame(1, 0xC359, 0x2000));
  // Outside 3-02 .. 3-03 (3-00 = min-max) nothing is sent.
  EXPECT_EQ(setpoint_frame("danfoss-fc51", 1, 1501), std::nullopt);
  EXPECT_EQ(setpoint_frame("danfoss-fc51", 1, -30), std::nullopt);
}

// 3-02 = 10 Hz, 3-03 = 60 Hz, 4 poles: 0 % is 300 rpm, 100 % 1800 rpm.
Profile fc51_10_to_60_hz() {
  return shipped_with(
      "danfoss-fc51",
      {{"min_reference_hz", 10.0}, {"max_reference_hz", 60.0}, {"motor_poles", 4.0}});
}

TEST(DanfossFc51Rpm, TheReferenceSpans3_02To3_03) {
  // 1050 rpm (35 Hz) is half the span, 2000 hex; 300 rpm is 0; below 3-02 nothing is sent.
  const Profile p = fc51_10_to_60_hz();
  EXPECT_EQ(setpoint_frame(p, 1, 1050), support::fc06_frame(1, 0xC359, 0x2000));
  EXPECT_EQ(setpoint_frame(p, 1, 300), support::fc06_frame(1, 0xC359, 0x0000));
  EXPECT_EQ(setpoint_frame(p, 1, 290), std::nullopt);
}

TEST(DanfossFc51Rpm, MavReadsAsTheSynchronousSpeedOverTheSameSpan) {
  // p.88: MAV is scaled as the reference. MAV = 2000 hex (50 %) with 3-02 = 10 Hz, 3-03 = 60 Hz:
  // 35 Hz, 1050 rpm at 4 poles; the register a PLC reads is 50210 (address C421h).
  const SpeedSeen seen =
      speed_seen(fc51_10_to_60_hz(), "set main_actual_value 50", {0x03, 0xC4, 0x21, 0x00, 0x01});
  EXPECT_EQ(seen.rpm, 1050);
  EXPECT_EQ(seen.reply, rtu({0x03, 0x02, 0x20, 0x00}));
}

// --- Eaton PowerXL DG1 ---

// P1.1 = 10 Hz, P1.2 = 60 Hz, 4 poles.
Profile dg1_10_to_60_hz() {
  return shipped_with(
      "eaton-dg1", {{"min_frequency_hz", 10.0}, {"max_frequency_hz", 60.0}, {"motor_poles", 4.0}});
}

TEST(EatonDg1Rpm, TheStartupTests50PercentReferenceIsHalfTheSpan) {
  // p.15: "Set FB Speed reference (Modbus Address 42002) value to 5000 (=50.00%)": at the
  // examples (P1.1 = 0, P1.2 = 50 Hz, 4 poles) 750 rpm; written with FC 06 at 2002 (07D2h).
  EXPECT_EQ(setpoint_frame("eaton-dg1", 1, 750), support::fc06_frame(1, 0x07D2, 5000));
  // P1.1 = 10 Hz, P1.2 = 60 Hz: 50 % is 35 Hz, 1050 rpm.
  EXPECT_EQ(setpoint_frame(dg1_10_to_60_hz(), 1, 1050), support::fc06_frame(1, 0x07D2, 5000));
}

TEST(EatonDg1Rpm, TheActualSpeedReadsAsTheSynchronousSpeedOverTheSameSpan) {
  // p.15: "The Actual value is 5000" (ID 2103, input register address 2102 = 0836h); p.134: the
  // actual value 0..10000 spans the set minimum .. maximum frequency. P1.1 = 10 Hz, P1.2 =
  // 60 Hz: 35 Hz, 1050 rpm at 4 poles.
  const SpeedSeen seen =
      speed_seen(dg1_10_to_60_hz(), "set fb_actual_speed 50", {0x04, 0x08, 0x36, 0x00, 0x01});
  EXPECT_EQ(seen.rpm, 1050);
  EXPECT_EQ(seen.reply, rtu({0x04, 0x02, 0x13, 0x88}));
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_shipped_rpm_test
