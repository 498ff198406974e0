// FC 08 Diagnostics on a serial line (MODBUS Application Protocol V1.1b3, "Application Protocol",
// 6.8): a serial listener's counters as the specification defines them, and the sub-functions
// that return or clear them. Pure: the listener counts, this answers. On Modbus TCP the function
// is not served (0x01): its counters describe a serial line.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "backend.h"

namespace drivegate::modbus {

// Application Protocol 6.8.1 (sub-functions 0x0B..0x12), and what a drivegate serial listener
// counts in each. The listener answers for several unit ids; these are the line's, shared by all.
struct SerialCounters {
  std::uint64_t bus_messages = 0;          // 0x0B: frames seen on the line, any address, good CRC
                                           //       or not
  std::uint64_t bus_comm_errors = 0;       // 0x0C: CRC / LRC errors
  std::uint64_t bus_exception_errors = 0;  // 0x0D: exception responses sent
  std::uint64_t server_messages = 0;       // 0x0E: requests for our units or broadcast, processed
  std::uint64_t server_no_response = 0;    // 0x0F: of those, not answered (broadcasts)
  std::uint64_t server_nak = 0;            // 0x10: exception 07 sent (never: always 0)
  std::uint64_t server_busy = 0;           // 0x11: exception 06 sent
  std::uint64_t bus_char_overruns = 0;     // 0x12: frames longer than the line allows
  // Not FC 08 counters: what else the listener saw, for /metrics and the status page.
  std::uint64_t broken_frames = 0;         // cut by a gap, or noise: discarded
  std::uint64_t other_units = 0;           // good requests for a unit nobody here serves
  std::uint64_t broadcasts = 0;            // address 0 requests
  std::uint64_t broadcasts_refused = 0;    // of those, writes not applied (broadcast = false)
  std::uint64_t write_timeouts = 0;        // write_reply = accepted: a write the drive failed
                                           //   after the master was told it was accepted
};

// Diagnostics sub-function codes (Application Protocol 6.8.1).
namespace diag {
inline constexpr std::uint16_t return_query_data = 0x00;
inline constexpr std::uint16_t return_diagnostic_register = 0x02;
inline constexpr std::uint16_t clear_counters = 0x0A;
inline constexpr std::uint16_t bus_message_count = 0x0B;
inline constexpr std::uint16_t bus_comm_error_count = 0x0C;
inline constexpr std::uint16_t bus_exception_error_count = 0x0D;
inline constexpr std::uint16_t server_message_count = 0x0E;
inline constexpr std::uint16_t server_no_response_count = 0x0F;
inline constexpr std::uint16_t server_nak_count = 0x10;
inline constexpr std::uint16_t server_busy_count = 0x11;
inline constexpr std::uint16_t bus_char_overrun_count = 0x12;
inline constexpr std::uint16_t clear_overrun_counter = 0x14;
}  // namespace diag

// Answers the FC 08 `request` PDU (function, sub-function, data) into `out` (at least
// kMaxPduSize bytes): the echo or the counter (its low 16 bits: the specification's counters are
// 16 bits and wrap), or the exception PDU: 01 for a sub-function not served (01, 03, 04 change
// how the line is listened to and are not offered), 03 for a data field not 0000 where the
// specification asks for it or a request of the wrong length. `counters` only ever grow (they are
// also /metrics' counters): a master's 0x0A or 0x14 moves `cleared` up to them instead, and each
// count returned is the difference. Returns the PDU size.
std::size_t diagnostics(std::span<const std::uint8_t> request, const SerialCounters& counters,
                        SerialCounters& cleared, std::span<std::uint8_t> out);

}  // namespace drivegate::modbus
