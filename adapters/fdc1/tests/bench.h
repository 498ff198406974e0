// The frames of the FDC1 document the tests expect on the wire, and a controller on the shared
// bench (tests/support/adapter_bench.h), in slave mode unless told otherwise: what hearing it and
// running it take on a streaming protocol.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"

namespace drivegate::fdc1 {

using namespace std::chrono_literals;
using namespace test::common_block;

// INPUT, Programming speed (decimal 72 115 min max 85 x), slave mode: stop is minimum 0 (with
// the in-range maximum 3500), a run minimum = maximum = the setpoint.
inline const Bytes kStopFrame = {0x48, 0x73, 0x00, 0x00, 0x0D, 0xAC, 0x55, 0xCF};
inline const Bytes kRun2000 = {0x48, 0x73, 0x07, 0xD0, 0x07, 0xD0, 0x55, 0x6E};
inline const Bytes kRun2500 = {0x48, 0x73, 0x09, 0xC4, 0x09, 0xC4, 0x55, 0x6E};
inline const Bytes kRun3000 = {0x48, 0x73, 0x0B, 0xB8, 0x0B, 0xB8, 0x55, 0x6E};

// The options of a controller the gateway runs (slave mode); the default ones only monitor.
inline const test::OptionText kSlave = {{"slave_mode", "true"}};

struct Bench : test::AdapterBench {
  explicit Bench(const test::BenchSetup& setup = {.options = kSlave})
      : AdapterBench(drivegate_adapter, setup) {}

  // Online (a first status heard), then the line idle again after the start-up frame.
  [[nodiscard]] bool ready() { return until_online(100ms); }
  // From ready (test::ReadyBench): "run at `rpm`" in one request, as a PLC writes it, confirmed
  // by the stream, and the ramp given time to reach `rpm` (1000 rpm/s from 1500 in the
  // simulator).
  [[nodiscard]] bool running_at(std::uint16_t rpm) {
    if (!run_forward_at(rpm)) return false;
    rig.run_for(3s);
    return read("speed_rpm") == rpm;
  }
  // Runs until the device heard its next status frame.
  [[nodiscard]] bool next_status() {
    const std::uint32_t before = read("frames_good");
    return rig.run_until([&] { return read("frames_good") > before; }, 1s);
  }
};

}  // namespace drivegate::fdc1
