#include "line_timing.h"

#include <algorithm>

namespace drivegate::modbus_device {
namespace {

// Serial Line 2.5.1.1: above 19200 baud the silence between frames is a fixed 1.75 ms.
constexpr std::chrono::nanoseconds kFixedSilence = std::chrono::microseconds(1750);

}  // namespace

std::chrono::nanoseconds wire_time(std::chrono::nanoseconds char_time, std::size_t bytes) {
  return char_time * static_cast<long>(bytes);
}

Millis reply_timeout(Millis timeout, std::chrono::nanoseconds char_time, std::size_t bytes) {
  return timeout + std::chrono::ceil<Millis>(wire_time(char_time, bytes));
}

Micros inter_frame_gap(Framing f, std::chrono::nanoseconds char_time) {
  if (f != Framing::rtu) return Micros(0);
  return std::chrono::ceil<Micros>(
      std::max<std::chrono::nanoseconds>(char_time * 7 / 2, kFixedSilence));
}

Millis exchange_time(Framing f, std::chrono::nanoseconds char_time, Millis reply_timeout,
                     std::uint8_t attempts, std::size_t longest) {
  return std::chrono::ceil<Millis>(attempts * (unanswered_attempt(reply_timeout) +
                                               inter_frame_gap(f, char_time) +
                                               wire_time(char_time, 2 * longest)));
}

Millis write_backstop(Millis one, int parts) {
  return std::max(kWriteTimeoutFloor, parts * (2 * one + kOtherTurnAllowance) + kDeadlineMargin);
}

}  // namespace drivegate::modbus_device
