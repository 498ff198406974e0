// How long things take on a Modbus serial line, for the two drivers of this adapter (the
// profile's and the pass-through one): the silence before a frame, the time frames take on the
// wire, and how long one exchange may hold the line. Pure arithmetic on the character time the
// bus really runs (DeviceEnv::char_time).
#pragma once

#include <chrono>
#include <cstddef>

#include "codec.h"
#include "drivegate/driver.h"

namespace drivegate::modbus_device {

// The longest frame: 256 bytes in RTU, 513 characters in ASCII (Serial Line 2.5.1.1, 2.5.2.1).
inline constexpr std::size_t kLongestRtu = 256;
inline constexpr std::size_t kLongestAscii = 513;
constexpr std::size_t longest_frame(Framing f) {
  return f == Framing::rtu ? kLongestRtu : kLongestAscii;
}

// `bytes` characters on the wire, exactly.
std::chrono::nanoseconds wire_time(std::chrono::nanoseconds char_time, std::size_t bytes);

// A reply timeout (whole milliseconds, as Exchange::timeout is) that waits `timeout` and the
// reply's `bytes` characters on the wire: the wire time rounded up once, at the end.
Millis reply_timeout(Millis timeout, std::chrono::nanoseconds char_time, std::size_t bytes);

// RTU frames are preceded by 3.5 characters of silence, at least a fixed 1.75 ms above 19200
// baud (Serial Line 2.5.1.1), rounded up to the next microsecond (never shorter than the
// specification's); ASCII frames start with ':' and need none.
Micros inter_frame_gap(Framing f, std::chrono::nanoseconds char_time);

// The most line time one exchange takes whose frames there and back are at most `longest` bytes
// each: every attempt's wait and the engine's guard after it, the gap and the frames, rounded up
// to whole milliseconds once (a deadline, not a silence).
Millis exchange_time(Framing f, std::chrono::nanoseconds char_time, Millis reply_timeout,
                     std::uint8_t attempts, std::size_t longest);

// The gateway's backstop for a write (DriverTraits::write_timeout) when one write holds at most
// `parts` exchanges, each taking at most `one` and waiting for another device's turn before it:
// never shorter than the driver's own deadlines.
Millis write_backstop(Millis one, int parts);

}  // namespace drivegate::modbus_device
