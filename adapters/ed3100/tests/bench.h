// The frames of the ED3100 document the tests expect on the wire, and an ED3100 at the document's
// address on the shared bench (tests/support/adapter_bench.h): what its start-up and its ramp
// take, and which frames are its writes.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"

namespace drivegate::ed3100 {

using namespace std::chrono_literals;
using namespace test::common_block;

// Document frames at address 0x1F (codec_test.cpp cites their sections).
inline const Bytes kReadParam{0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5};
inline const Bytes kWriteParam{0x1F, 0x06, 0x00, 0x06, 0x13, 0x88, 0x67, 0x23};
inline const Bytes kReadMonitor{0x1F, 0x03, 0x0D, 0x00, 0x00, 0x00, 0x44, 0xD8};
inline const Bytes kReadFault{0x1F, 0x03, 0x0E, 0x01, 0x00, 0x00, 0x15, 0x5C};
inline const Bytes kForward{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04,
                            0x00, 0x1E, 0x10, 0x88, 0x67, 0xE6};
inline const Bytes kReverse{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04,
                            0x00, 0x2E, 0x10, 0x88, 0x67, 0xE9};
inline const Bytes kRunReply{0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x49, 0xB6};
inline const Bytes kStop{0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74};

inline constexpr std::uint32_t kFaultOther = 17;  // Fault::other
// This adapter's holding points with parameters = "00-06": frequency_setpoint, param_00_06.
inline constexpr std::uint16_t kFrequencyRegister = 16;
inline constexpr std::uint16_t kParam0006Register = 17;
// Its fault_code point, which shares its name with the common block's (input 1).
inline constexpr std::uint16_t kFaultCodePoint = 32;

inline const test::OptionText kWithParameter{{"parameters", "00-06"}};

struct Bench : test::AdapterBench {
  // The drive at the document's address 0x1F with parameter 00-06 exposed, unless told otherwise;
  // the simulator gets the same options (it reads sim_reply_form).
  explicit Bench(const test::OptionText& options = kWithParameter)
      : AdapterBench(drivegate_adapter, {.options = options, .address = 0x1F}) {}

  // Online, and the first poll cycle (the monitors after the fault word) is in: the line is idle.
  [[nodiscard]] bool ready() { return until_online(200ms); }
  // From ready (test::ReadyBench): "run forward at `rpm`" in one request, as a PLC writes it,
  // and the ramp to that speed.
  [[nodiscard]] bool running_at(std::int32_t rpm) {
    return run_forward_at(static_cast<std::uint16_t>(rpm)) &&
           rig.run_until([&] { return read_i16("speed_rpm") == rpm; }, 3s);
  }

  // Writes (06 and 10) on the wire from `from` on: polls are 03.
  [[nodiscard]] std::vector<Bytes> writes(TimePoint from = {}) const {
    std::vector<Bytes> out;
    for (const Bytes& f : frames(from)) {
      if (f.size() > 1 && f[1] != kFnRead) out.push_back(f);
    }
    return out;
  }
};

}  // namespace drivegate::ed3100
