// The one-shot requests of holding point `action`, written as a PLC writes them, on the real bus
// engine: the frame of section 5 on the wire, `action_status`, and the points their ACKs fill.
#include <gtest/gtest.h>

#include "bench.h"
#include "points.h"

namespace drivegate::nidec {
namespace {

constexpr std::uint16_t value_of(Action a) {
  return static_cast<std::uint16_t>(a);
}
constexpr std::uint32_t status_of(ActionStatus s) {
  return static_cast<std::uint32_t>(s);
}

// `action` written to holding point `action` as a PLC writes it: taken, and `frame` the first the
// master sent after the write.
testing::AssertionResult sends(Bench& b, Action action, const Bytes& frame) {
  const TimePoint asked = b.rig.now();
  if (const auto result = b.write("action", {value_of(action)}); result != Outcome::ok) {
    return testing::AssertionFailure()
           << "the action ended " << (result ? static_cast<int>(*result) : -1) << " (-1: never)";
  }
  const std::vector<Bytes> sent = b.frames(asked);
  if (sent.empty() || sent[0] != frame) {
    return testing::AssertionFailure() << "the first frame after the write is not the action's";
  }
  return testing::AssertionSuccess();
}

using NidecActions = test::ReadyBench<Bench>;

TEST_F(NidecActions, VoltageDetection_5_9) {
  EXPECT_EQ(b.read("action_status"), status_of(ActionStatus::idle));
  const TimePoint asked = b.rig.now();
  const auto w = b.start_write("action", {value_of(Action::voltage_detection)});
  EXPECT_EQ(b.read("action_status"), status_of(ActionStatus::pending));
  EXPECT_EQ(b.rig.wait(w), Outcome::ok);
  EXPECT_EQ(b.frames(asked).at(0),
            (Bytes{0xA5, 0x2B, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8E}));
  EXPECT_EQ(b.read("dc_bus_voltage"), 311u);
  EXPECT_EQ(b.read("action"), value_of(Action::voltage_detection));
  EXPECT_EQ(b.read("action_status"), status_of(ActionStatus::done));
}

TEST_F(NidecActions, WeightDetectionTakes35s_5_10) {
  EXPECT_EQ(b.write("action", {value_of(Action::weight_detection)}), Outcome::ok);
  EXPECT_EQ(b.read("raw_weight"), 0u);  // 5.10: 0 until detected
  EXPECT_EQ(b.read("weight"), 0u);
  b.rig.run_for(36s);
  EXPECT_EQ(b.read("weight"), 35u);  // 3.5 kg: the Request ACK (5.2) reports it too
  EXPECT_EQ(b.write("action", {value_of(Action::weight_detection)}), Outcome::ok);
  EXPECT_EQ(b.read("raw_weight"), 1700u);
}

TEST_F(NidecActions, FabricDetectionIsKeptRaw_5_11) {
  b.control("fabric 3");
  EXPECT_TRUE(sends(b, Action::fabric_detection,
                    Bytes{0xA5, 0x2D, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x88}));
  EXPECT_EQ(b.read("fabric_raw"), 0x00030000u);
}

TEST_F(NidecActions, ForcedBrakeBlocksAndStopsMotion_5_13) {
  ASSERT_TRUE(b.running_at(800));
  EXPECT_TRUE(sends(b, Action::forced_brake_enable,
                    Bytes{0xA5, 0x1B, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xBF}));
  EXPECT_EQ(b.read("forced_brake"), 1u);
  // 5.13: the motor is held stopped: no run is in force, and none is taken.
  EXPECT_EQ(b.read("command"), cmd::stop);
  const std::size_t before = b.rig.sent().size();
  EXPECT_EQ(b.start_write({cmd::run_forward})->result, Outcome::refused);
  EXPECT_EQ(b.rig.sent().size(), before);
  EXPECT_TRUE(sends(b, Action::forced_brake_disable,
                    Bytes{0xA5, 0x1B, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xBE}));
  EXPECT_EQ(b.read("forced_brake"), 0u);
  EXPECT_EQ(b.write({cmd::run_forward}), Outcome::ok);
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

TEST_F(NidecActions, FctTest_5_15) {
  b.control("fault stall");
  EXPECT_TRUE(sends(b, Action::fct_test, kFct));
  EXPECT_EQ(b.read("fct_error"), 0x0008u);
  EXPECT_EQ(b.read("fct_speed_rpm"), 0u);
  EXPECT_EQ(b.read("fct_ipm_temperature"), 45u);
  EXPECT_EQ(b.read("fct_ipm_model_bus_volt_high"), 0x11u);
  EXPECT_EQ(b.read("fct_bus_volt_low"), 0x37u);
  EXPECT_EQ(b.read("fct_phase_current"), 0u);
  // Its 16-bit Error is not the section 8 byte: the common faults wait for the next poll.
  EXPECT_EQ(b.read("native_fault"), 0u);
}

TEST_F(NidecActions, PingAgainOnRequest_5_1) {
  b.control("version 0x0203");
  EXPECT_TRUE(sends(b, Action::ping, kPing7));
  EXPECT_EQ(b.read("inverter_version"), 0x0203u);
  // `none` is taken without traffic; the gateway keeps values the table does not name.
  const std::size_t before = b.rig.sent().size();
  EXPECT_EQ(b.start_write("action", {value_of(Action::none)})->result, Outcome::ok);
  EXPECT_EQ(b.rig.sent().size(), before);
  EXPECT_EQ(b.read("action"), value_of(Action::none));
  EXPECT_EQ(b.write("action", {8}), Outcome::invalid_value);
  EXPECT_EQ(b.read("action_status"), status_of(ActionStatus::done));
}

TEST_F(NidecActions, AnUnansweredActionIsNoResponse) {
  b.control("silent on");
  EXPECT_EQ(b.write("action", {value_of(Action::voltage_detection)}), Outcome::no_response);
  EXPECT_EQ(b.read("action_status"), status_of(ActionStatus::no_response));
  EXPECT_EQ(b.read("dc_bus_voltage"), 0u);
}

}  // namespace
}  // namespace drivegate::nidec
