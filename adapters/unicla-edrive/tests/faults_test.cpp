// The fault mapping (README.md, "Fault mapping"): the safety flags and the Fault-* operating
// states onto the unified faults, warnings, and what the op states say about running.
#include "faults.h"

#include <gtest/gtest.h>

#include "op_state.h"

namespace drivegate::unicla {
namespace {

TEST(UniclaFaults, MotorFlagsMapToUnifiedCodes) {
  // "Motor Safety Flags - Run, Start", bit by bit.
  EXPECT_TRUE(map_motor_flags(1u << 14).has(Fault::over_current));
  EXPECT_TRUE(map_motor_flags(1u << 9).has(Fault::over_voltage));
  EXPECT_TRUE(map_motor_flags(1u << 10).has(Fault::under_voltage));
  EXPECT_TRUE(map_motor_flags(1u << 11).has(Fault::drive_over_temperature));
  EXPECT_TRUE(map_motor_flags(1u << 2).has(Fault::drive_over_temperature));
  EXPECT_TRUE(map_motor_flags(1u << 4).has(Fault::motor_over_temperature));
  EXPECT_TRUE(map_motor_flags(1u << 12).has(Fault::stall));
  EXPECT_TRUE(map_motor_flags(1u << 13).has(Fault::stall));
  EXPECT_TRUE(map_motor_flags(1u << 5).has(Fault::overload));
  EXPECT_TRUE(map_motor_flags(1u << 7).has(Fault::hardware_fault));
  EXPECT_TRUE(map_motor_flags(1u << 15).has(Fault::internal_error));
  EXPECT_TRUE(map_motor_flags(1u << 1).has(Fault::other));
  EXPECT_TRUE(map_motor_flags(1u << 0).empty());      // "X"
  EXPECT_TRUE(map_compressor_flags(0x000F).empty());  // bits 0-3 "X"
  EXPECT_TRUE(map_compressor_flags(0x0010).has(Fault::process_limit));
  EXPECT_TRUE(map_compressor_flags(0x8000).has(Fault::process_limit));
  EXPECT_TRUE(map_electrical_flags(0xF800).empty());  // bits 11-15 "X"
  EXPECT_TRUE(map_electrical_flags(1u << 23).has(Fault::hardware_fault));
  EXPECT_TRUE(map_electrical_flags(1u << 0).has(Fault::hardware_fault));
  EXPECT_TRUE(map_electrical_flags(1u << 24).empty());  // 24 bits only
}

TEST(UniclaFaults, OpStatesMapToUnifiedCodes) {
  Status s;
  const auto faults_of = [&s](OpState st) {
    s.op_state = static_cast<std::uint8_t>(st);
    return map_faults(s);
  };
  EXPECT_TRUE(faults_of(OpState::fault_compressor_safety).faults.has(Fault::process_limit));
  EXPECT_TRUE(faults_of(OpState::fault_motor).faults.has(Fault::other));  // no flag says more
  EXPECT_TRUE(faults_of(OpState::fault_fmc).faults.has(Fault::hardware_fault));
  EXPECT_TRUE(faults_of(OpState::fault_electrical).faults.has(Fault::hardware_fault));
  EXPECT_TRUE(faults_of(OpState::fault_configuration).faults.has(Fault::config_error));
  EXPECT_TRUE(faults_of(OpState::fault_xc_comms).faults.has(Fault::comm_lost));
  EXPECT_EQ(faults_of(OpState::fault_xc_comms).native, 11u);
  EXPECT_TRUE(faults_of(OpState::running).faults.empty());
  EXPECT_EQ(faults_of(OpState::running).native, 0u);
  EXPECT_FALSE(faults_of(OpState::running).warning);
  EXPECT_TRUE(faults_of(OpState::wait_compressor_safety).warning);
  EXPECT_TRUE(faults_of(OpState::locked).warning);
  EXPECT_TRUE(faults_of(OpState::motor_thermal_inhibit).warning);
  s.motor_run_flags = 1u << 14;
  const FaultView motor = faults_of(OpState::fault_motor);
  EXPECT_TRUE(motor.faults.has(Fault::over_current));
  EXPECT_FALSE(motor.faults.has(Fault::other));
  // The same flag while running is a warning, not a fault.
  const FaultView running = faults_of(OpState::running);
  EXPECT_TRUE(running.faults.empty());
  EXPECT_TRUE(running.warning);
  // The start word counts as the run word does.
  s.motor_run_flags = 0;
  s.motor_start_flags = 1u << 12;
  EXPECT_TRUE(faults_of(OpState::fault_motor).faults.has(Fault::stall));
}

TEST(UniclaFaults, FlagLabelsNameTheDocumentsBits) {
  const auto motor = motor_flag_labels();
  ASSERT_EQ(motor.size(), 15u);
  EXPECT_EQ(motor[0].name, "Switch Temperature Low");
  EXPECT_EQ(motor[0].value, 1u);
  const auto electrical = electrical_flag_labels();
  ASSERT_EQ(electrical.size(), 19u);
  EXPECT_EQ(electrical[10].name, "FMC CT 5V High");
  EXPECT_EQ(electrical[10].value, 10u);
  EXPECT_EQ(electrical[11].name, "CMC 3V3 Fault");
  EXPECT_EQ(electrical[11].value, 16u);
  EXPECT_EQ(compressor_flag_labels().back().name, "High Side Pressure Low");
}

TEST(UniclaOpState, WhatAStateSaysAboutRunning) {
  const auto u8 = [](OpState s) { return static_cast<std::uint8_t>(s); };
  EXPECT_TRUE(is_running_state(u8(OpState::starting)));
  EXPECT_TRUE(is_running_state(u8(OpState::running)));
  EXPECT_TRUE(is_running_state(u8(OpState::oil_balance_running)));
  EXPECT_FALSE(is_running_state(u8(OpState::stopped)));
  EXPECT_TRUE(took_run(u8(OpState::wait_anti_short)));
  EXPECT_TRUE(took_run(u8(OpState::oil_balance_run_wait)));
  EXPECT_FALSE(took_run(u8(OpState::stopped)));
  EXPECT_TRUE(refuses_run(u8(OpState::not_ready)));
  EXPECT_TRUE(refuses_run(u8(OpState::fault_motor)));
  EXPECT_TRUE(refuses_run(u8(OpState::locked)));
  EXPECT_TRUE(refuses_run(u8(OpState::motor_thermal_inhibit)));
  EXPECT_TRUE(refuses_run(kOpStateCount));  // not in the document
  EXPECT_FALSE(refuses_run(u8(OpState::stopped)));
  EXPECT_FALSE(is_fault_state(u8(OpState::wait_compressor_safety)));
  EXPECT_TRUE(is_fault_state(u8(OpState::fault_xc_comms)));
  EXPECT_FALSE(is_fault_state(u8(OpState::locked)));
}

}  // namespace
}  // namespace drivegate::unicla
