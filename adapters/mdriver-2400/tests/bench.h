// The frames of the compressor driver's document the tests expect on the wire, and a driver on
// the shared bench (tests/support/adapter_bench.h): what its start-up and a run take, and a drive
// that answers other than it was told.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"

namespace drivegate::mdriver {

using namespace std::chrono_literals;
using namespace test::common_block;

// Section 3 No.1: the fixed-code check.
inline const Bytes kCheck{0x00, 0x01, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x38};
// Conversion table <通常運転モード>, rows 01 (stop), 00 (reset & stop), 40 (1149 rpm),
// 1C (504 rpm); <連続運転モード> row 40.
inline const Bytes kRunStop{0x00, 0x01, 0x10, 0x02, 0x01, 0x01, 0x00, 0x40};
inline const Bytes kRunReset{0x00, 0x01, 0x10, 0x02, 0x00, 0x01, 0x00, 0x41};
inline const Bytes kRun1149{0x00, 0x01, 0x10, 0x02, 0x40, 0x01, 0x00, 0x01};
inline const Bytes kRun504{0x00, 0x01, 0x10, 0x02, 0x1C, 0x01, 0x00, 0x25};
inline const Bytes kRun1149Continuous{0x00, 0x01, 0x10, 0x02, 0x40, 0xFF, 0x00, 0x03};

// A run reply as the drive sent it, with R4 (target) and R7 (error) replaced: a drive that does
// not take what it was sent. Other bytes pass unchanged.
inline Bytes with_reply(Bytes reply, std::uint8_t target, std::uint8_t error) {
  // Section 3 No.2: R0 src, R1 dst, R2 command 10, R3 07, R4 target .. R7 error .. R12 checksum.
  if (reply.size() != 13 || reply[2] != 0x10) return reply;
  reply[4] = target;
  reply[7] = error;
  reply[12] = checksum(ByteView(reply).first(12));
  return reply;
}

struct Bench : test::AdapterBench {
  explicit Bench(const test::BenchSetup& setup = {}) : AdapterBench(drivegate_adapter, setup) {}

  // Online, and the first run reply (the status) is in: the line is idle.
  [[nodiscard]] bool ready() { return until_online(200ms); }
  // From ready (test::ReadyBench): "run at 1149 rpm" in one request, as a PLC writes it,
  // confirmed, then a second of ramp.
  [[nodiscard]] bool running_at_1149() {
    if (!run_forward_at(1149)) return false;
    rig.run_for(1s);
    return true;
  }
};

}  // namespace drivegate::mdriver
