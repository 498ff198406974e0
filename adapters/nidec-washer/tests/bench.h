// The frames of the washer inverter's document the tests expect on the wire, and an inverter on
// the shared bench (tests/support/adapter_bench.h), on its one-wire line at 4800 8O1: what its
// handshake, a run and a poll take.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"

namespace drivegate::nidec {

using namespace std::chrono_literals;
using namespace test::common_block;

// Master frames (4.1), each laid out per the section cited.
inline const Bytes kPing7{0xA5, 0x02, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0};  // 5.1
inline const Bytes kPoll{0xA5, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0};   // 5.2
inline const Bytes kCw800{0xA5, 0x09, 0x03, 0x20, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x91};  // 5.3
inline const Bytes kCw1000{0xA5, 0x09, 0x03, 0xE8, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x59};
inline const Bytes kCcw800{0xA5, 0x0B, 0x03, 0x20, 0x00, 0x1E,
                           0x00, 0x00, 0x00, 0x00, 0x93};                                     // 5.4
inline const Bytes kStop{0xA5, 0x27, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x82};   // 5.7
inline const Bytes kBrake{0xA5, 0x29, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8C};  // 5.8
inline const Bytes kFct{0xA5, 0x66, 0x12, 0x00, 0x34, 0x00, 0x56, 0x00, 0x78, 0x00, 0xCB};  // 5.15

struct Bench : test::AdapterBench {
  explicit Bench(const test::BenchSetup& setup = {}) : AdapterBench(drivegate_adapter, setup) {}

  // Online: the ping (5.1) is answered and the line is idle.
  [[nodiscard]] bool ready() { return until_online(0ms, 1s); }
  // From ready (test::ReadyBench): "run forward at `rpm`" in one request, as a PLC writes it,
  // confirmed, then the 3.0 s ramp.
  [[nodiscard]] bool running_at(std::uint16_t rpm, std::uint16_t command = cmd::run_forward) {
    if (write({command, rpm}) != Outcome::ok) return false;
    rig.run_for(4s);
    return read("speed_rpm") == rpm;
  }
  // Runs until the next poll has been answered: the driver knows what the inverter reported, and
  // the line is idle for the poll interval.
  [[nodiscard]] bool after_next_poll() {
    if (!next_poll_on_the_line()) return false;
    rig.run_for(60ms);  // the poll's echo and its 7-byte ACK at 4800 baud
    return true;
  }
  // Runs until the next poll has gone on the line: a write now waits for its answer.
  [[nodiscard]] bool next_poll_on_the_line() {
    const std::size_t polls = count(kPoll);
    return rig.run_until([&] { return count(kPoll) > polls; }, 2s);
  }
};

}  // namespace drivegate::nidec
