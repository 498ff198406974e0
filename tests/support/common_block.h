// The common register block every device starts with, as a PLC addresses it
// (docs/register-map.md): the holding registers command and setpoint_rpm, the values command
// takes, and the bits of input register status. The tests state them here, once, rather than
// take them from the gateway's code, so that a change to the documented map fails the tests.
//
//   using namespace test::common_block;
//   EXPECT_EQ(b.write({cmd::run_forward, 1500}), Outcome::ok);  // holding 0..1
//   EXPECT_NE(b.read("status") & kRunning, 0u);
#pragma once

#include <cstdint>

namespace drivegate::test::common_block {

inline constexpr std::uint16_t kCommandRegister = 0;
inline constexpr std::uint16_t kSetpointRegister = 1;

// The values of holding register command.
namespace cmd {
inline constexpr std::uint16_t stop = 0, run_forward = 1, run_reverse = 2, quick_stop = 3,
                               reset_fault = 4;
}  // namespace cmd

// Input register status (30001), then fault_code (30002).
inline constexpr std::uint16_t kStatusRegister = 0;
inline constexpr std::uint16_t kFaultCodeRegister = 1;

// The bits of input register status.
inline constexpr std::uint16_t kOnline = 1u << 0, kRunning = 1u << 1, kFaulted = 1u << 2,
                               kWarning = 1u << 3, kCommLost = 1u << 4, kFailsafe = 1u << 5,
                               kCommandPending = 1u << 6;

}  // namespace drivegate::test::common_block
