// The test-drive protocol: a made-up drive protocol that only the core's tests speak, so that
// they run on a plugin of their own (tests/support/test_adapter/README.md) and a production
// adapter can change without breaking them. Pure: bytes in, frames out.
//
//   request (6 bytes): 0x3C address op arg_hi arg_lo sum
//   reply   (8 bytes): 0x3E address op state fault speed_hi speed_lo sum
//   refusal (8 bytes): 0x3F address op 00 00 00 00 sum   (a NAK: the drive did not take it)
//
// `sum` makes every byte of the frame add up to 0 (mod 256). Ops: read, run_forward and
// run_reverse (arg: rpm), stop, reset (the fault), accel (arg: the time from 0 to kMaxRpm, in
// 100 ms units). The reply echoes the op and carries the state after it: bit 0 running, bit 1
// reverse; the fault code (0 none); the speed in rpm, signed. A refusal echoes the op and
// carries nothing: the request was not acted on, and may be sent again.
#pragma once

#include <cstdint>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"

namespace drivegate::testdrive {

inline constexpr std::uint8_t kRequestStart = 0x3C;
inline constexpr std::uint8_t kReplyStart = 0x3E;
inline constexpr std::uint8_t kRefusalStart = 0x3F;
inline constexpr std::size_t kRequestSize = 6;
inline constexpr std::size_t kReplySize = 8;
inline constexpr std::uint8_t kStateRunning = 0x01;
inline constexpr std::uint8_t kStateReverse = 0x02;
// The fastest the drive turns either way; a run asks for 0..kMaxRpm.
inline constexpr std::uint16_t kMaxRpm = 3000;
// The accel time a drive starts with (op accel's arg, 100 ms units): 0 to kMaxRpm in 1.5 s.
inline constexpr std::uint16_t kDefaultAccel100ms = 15;

enum class Op : std::uint8_t {
  read = 1,
  run_forward = 2,
  run_reverse = 3,
  stop = 4,
  reset = 5,
  accel = 6
};

// Native fault codes and what the simulator's `fault NAME` sets.
enum class NativeFault : std::uint8_t {
  none = 0,
  over_current = 1,
  stall = 2,
  over_temperature = 3
};

struct Request {
  std::uint8_t address = 1;
  Op op = Op::read;
  std::uint16_t arg = 0;
  friend bool operator==(const Request&, const Request&) = default;
};

struct Reply {
  std::uint8_t address = 1;
  Op op = Op::read;
  std::uint8_t state = 0;
  std::uint8_t fault = 0;
  std::int16_t speed_rpm = 0;
  bool refused = false;  // a refusal (0x3F): the other fields are 0
  friend bool operator==(const Reply&, const Reply&) = default;
};

// The byte that makes `frame` (without it) add up to 0.
std::uint8_t sum_byte(ByteView frame);
[[nodiscard]] bool known_op(std::uint8_t op);

Bytes encode(const Request& r);
Bytes encode(const Reply& r);
// The refusal of `op` by the drive at `address`.
Reply refusal(std::uint8_t address, Op op);
// At the front of `rx`: incomplete until a whole frame is there; noise for a byte that cannot
// start one (consumed 1); a bad checksum or an unknown op consumes the frame. A reply is either
// kind, 0x3E or 0x3F.
Decoded<Request> decode_request(ByteView rx);
Decoded<Reply> decode_reply(ByteView rx);

}  // namespace drivegate::testdrive
