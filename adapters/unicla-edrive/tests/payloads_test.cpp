// Payload layouts ("Status", "Build Information", "Running Limits/ RS485 Config"): hand-built
// byte vectors, both float byte orders, round trips.
#include "payloads.h"

#include <gtest/gtest.h>

namespace drivegate::unicla {
namespace {

// A Status payload laid out by hand, rows of 8 bytes as in the "Status" table.
Bytes hand_status_big() {
  Bytes p(kStatusSize, 0);
  const auto put = [&p](std::size_t at, std::initializer_list<std::uint8_t> b) {
    std::copy(b.begin(), b.end(), p.begin() + static_cast<long>(at));
  };
  put(0, {0x40, 0x60, 0x00, 0x00});                           // suction pressure 3.5 bar-a
  put(4, {0x41, 0x64, 0x00, 0x00});                           // discharge pressure 14.25 bar-a
  put(8, {0xC0, 0x00, 0x00, 0x00});                           // suction temperature -2.0 degC
  put(12, {0x42, 0x82, 0x00, 0x00});                          // discharge temperature 65.0 degC
  put(16, {0x40, 0xD0, 0x00, 0x00});                          // suction superheat 6.5 K
  put(20, {0x41, 0xA0, 0x00, 0x00});                          // discharge superheat 20.0 K
  put(24, {0x0B, 0xB8, 0x00, 0x1B, 0x03, 0xE8, 0x00, 0x03});  // 3000 rpm, 27 V, 1000 W, 3 Nm
  put(32, {0x02, 0x04, 0x32, 0x01, 0x00});  // Running, External Serial, 50 %, enabled, 0
  put(40, {0x42, 0x20, 0x00, 0x00});        // motor temperature 40.0
  put(44, {0x42, 0x34, 0x00, 0x00});        // switch temperature 45.0
  put(48, {0x40, 0x00, 0x00, 0x20, 0x40, 0x00, 0x00, 0x10});
  put(56, {0x81, 0x00, 0x02});  // CMC 3V3 Fault (16), CMC UDPC VCC High (23), FMC 3.3V (1)
  return p;
}

TEST(UniclaPayloads, StatusFromHandBuiltBytes) {
  const auto s = parse_status(hand_status_big(), ByteOrder::big);
  ASSERT_TRUE(s);
  EXPECT_FLOAT_EQ(s->suction_pressure, 3.5F);
  EXPECT_FLOAT_EQ(s->discharge_pressure, 14.25F);
  EXPECT_FLOAT_EQ(s->suction_temperature, -2.0F);
  EXPECT_FLOAT_EQ(s->discharge_temperature, 65.0F);
  EXPECT_FLOAT_EQ(s->suction_superheat, 6.5F);
  EXPECT_FLOAT_EQ(s->discharge_superheat, 20.0F);
  EXPECT_EQ(s->rpm, 3000);
  EXPECT_EQ(s->volts, 27);
  EXPECT_EQ(s->watts, 1000);
  EXPECT_EQ(s->torque, 3);
  EXPECT_EQ(s->op_state, 2);
  EXPECT_EQ(s->control_mode, 4);
  EXPECT_EQ(s->demand, 50);
  EXPECT_EQ(s->remote_enable, 1);
  EXPECT_EQ(s->anti_short, 0);
  EXPECT_FLOAT_EQ(s->motor_temperature, 40.0F);
  EXPECT_FLOAT_EQ(s->switch_temperature, 45.0F);
  EXPECT_EQ(s->compressor_run_flags, 0x4000);
  EXPECT_EQ(s->compressor_start_flags, 0x0020);
  EXPECT_EQ(s->motor_run_flags, 0x4000);
  EXPECT_EQ(s->motor_start_flags, 0x0010);
  EXPECT_EQ(s->electrical_flags, 0x810002u);
  EXPECT_EQ(encode_status(*s, ByteOrder::big), hand_status_big());
}

TEST(UniclaPayloads, LittleEndianFloatsOnlyFlipFloats) {
  Bytes p = hand_status_big();
  // Reverse each float; integers stay big-endian (the document's 03 E8).
  for (std::size_t at : {0, 4, 8, 12, 16, 20, 40, 44}) {
    std::reverse(p.begin() + static_cast<long>(at), p.begin() + static_cast<long>(at + 4));
  }
  const auto s = parse_status(p, ByteOrder::little);
  ASSERT_TRUE(s);
  EXPECT_FLOAT_EQ(s->suction_pressure, 3.5F);
  EXPECT_FLOAT_EQ(s->switch_temperature, 45.0F);
  EXPECT_EQ(s->rpm, 3000);
  EXPECT_EQ(encode_status(*s, ByteOrder::little), p);
  // Read with the wrong order, the floats are garbage but the integers still hold.
  const auto wrong = parse_status(p, ByteOrder::big);
  ASSERT_TRUE(wrong);
  EXPECT_NE(wrong->suction_pressure, 3.5F);
  EXPECT_EQ(wrong->rpm, 3000);
}

TEST(UniclaPayloads, ShortPayloadsRejectedLongerAccepted) {
  Bytes p = hand_status_big();
  p.pop_back();
  EXPECT_FALSE(parse_status(p, ByteOrder::big));
  p = hand_status_big();
  p.push_back(0xAA);
  EXPECT_TRUE(parse_status(p, ByteOrder::big));
  EXPECT_FALSE(parse_build_info(Bytes(79, 0), ByteOrder::big));
  EXPECT_FALSE(parse_running_limits(Bytes(63, 0), ByteOrder::big));
}

TEST(UniclaPayloads, BuildInformationLayout) {
  Bytes p(kBuildInfoSize, 0);
  const std::string model = "UNI-ED34";
  const std::string serial = "SN0123456789ABCD";  // all 16 characters used
  std::copy(model.begin(), model.end(), p.begin());
  std::copy(serial.begin(), serial.end(), p.begin() + 16);
  const Bytes comp = {0x02, 0x05, 0x00, 0x00, 0x03, 0xE8, 0x19, 0x64};  // R1234YF POE68 1000 6500
  std::copy(comp.begin(), comp.end(), p.begin() + 32);
  const Bytes elec = {0x00, 0x18, 0x09, 0xC4};  // 24 V, 2500 W
  std::copy(elec.begin(), elec.end(), p.begin() + 40);
  const std::string name = "Bus 7 front compressor   ";  // trailing spaces are dropped
  std::copy(name.begin(), name.end(), p.begin() + 48);
  const auto b = parse_build_info(p, ByteOrder::big);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->model, "UNI-ED34");
  EXPECT_EQ(b->serial, serial);
  EXPECT_EQ(b->refrigerant, 2);
  EXPECT_EQ(b->oil, 5);
  EXPECT_EQ(b->min_speed, 1000);
  EXPECT_EQ(b->max_speed, 6500);
  EXPECT_EQ(b->voltage, 24);
  EXPECT_EQ(b->power, 2500);
  EXPECT_EQ(b->device_name, "Bus 7 front compressor");
  const auto again = parse_build_info(encode_build_info(*b, ByteOrder::big), ByteOrder::big);
  EXPECT_EQ(again, b);
}

TEST(UniclaPayloads, RunningLimitsLayout) {
  Bytes p(kRunningLimitsSize, 0);
  const Bytes speed = {0x05, 0xDC, 0x17, 0x70};  // 1500 .. 6000 rpm
  std::copy(speed.begin(), speed.end(), p.begin());
  const Bytes sp = {0x3F, 0x80, 0x00, 0x00, 0x40, 0xC0, 0x00, 0x00};  // 1.0 .. 6.0 bar-a
  std::copy(sp.begin(), sp.end(), p.begin() + 8);
  const Bytes rs485 = {0x07, 0x00, 0x00, 0x01};  // device 7, control enabled
  std::copy(rs485.begin(), rs485.end(), p.begin() + 56);
  const auto l = parse_running_limits(p, ByteOrder::big);
  ASSERT_TRUE(l);
  EXPECT_EQ(l->min_speed, 1500);
  EXPECT_EQ(l->max_speed, 6000);
  EXPECT_FLOAT_EQ(l->suction_pressure.low, 1.0F);
  EXPECT_FLOAT_EQ(l->suction_pressure.high, 6.0F);
  EXPECT_EQ(l->device_id, 7);
  EXPECT_EQ(l->control_enabled, 1);
  EXPECT_EQ(encode_running_limits(*l, ByteOrder::big), p);
}

// "Commands / Set Run State": u16, 1000 rpm = 03 E8 ("Examples").
TEST(UniclaPayloads, SpeedIsBigEndian) {
  EXPECT_EQ(encode_speed(1000), (Bytes{0x03, 0xE8}));
  EXPECT_EQ(parse_speed(Bytes{0x03, 0xE8}), 1000);
  EXPECT_FALSE(parse_speed(Bytes{0x03}));
}

}  // namespace
}  // namespace drivegate::unicla
