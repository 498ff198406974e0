#include "diagnostics.h"

#include <algorithm>
#include <array>

#include "pdu.h"

namespace drivegate::modbus {

namespace {

constexpr std::uint8_t kFunction = 0x08;  // Application Protocol 6.8

std::size_t echo_with(std::span<const std::uint8_t> request, std::uint64_t value,
                      std::span<std::uint8_t> out) {
  out[0] = kFunction;
  out[1] = request[1];
  out[2] = request[2];
  const auto v = static_cast<std::uint16_t>(value & 0xFFFF);  // 16-bit counters wrap (6.8.1)
  out[3] = static_cast<std::uint8_t>(v >> 8);
  out[4] = static_cast<std::uint8_t>(v & 0xFF);
  return 5;
}

// The counter each of sub-functions 0x0B..0x12 returns, in order (6.8.1).
using Counter = std::uint64_t SerialCounters::*;
constexpr std::array<Counter, diag::bus_char_overrun_count - diag::bus_message_count + 1>
    kCounterOf = {
        &SerialCounters::bus_messages,         &SerialCounters::bus_comm_errors,
        &SerialCounters::bus_exception_errors, &SerialCounters::server_messages,
        &SerialCounters::server_no_response,   &SerialCounters::server_nak,
        &SerialCounters::server_busy,          &SerialCounters::bus_char_overruns,
};

}  // namespace

std::size_t diagnostics(std::span<const std::uint8_t> request, const SerialCounters& counters,
                        SerialCounters& cleared, std::span<std::uint8_t> out) {
  // Function, sub-function (2), data (2 or more): 6.8's request.
  if (request.size() < 5) return exception_pdu(kFunction, Exception::illegal_data_value, out);
  const auto sub = static_cast<std::uint16_t>(request[1] << 8 | request[2]);
  if (sub == diag::return_query_data) {  // the whole request back, data as sent (6.8.1, 00)
    std::copy(request.begin(), request.end(), out.begin());
    return request.size();
  }
  // Every other sub-function served takes exactly 0000 as its data.
  const bool served = sub == diag::return_diagnostic_register || sub == diag::clear_counters ||
                      (sub >= diag::bus_message_count && sub <= diag::bus_char_overrun_count) ||
                      sub == diag::clear_overrun_counter;
  if (!served) return exception_pdu(kFunction, Exception::illegal_function, out);
  if (request.size() != 5 || request[3] != 0 || request[4] != 0) {
    return exception_pdu(kFunction, Exception::illegal_data_value, out);
  }
  if (sub >= diag::bus_message_count && sub <= diag::bus_char_overrun_count) {
    const auto counter = kCounterOf[sub - diag::bus_message_count];
    return echo_with(request, counters.*counter - cleared.*counter, out);
  }
  switch (sub) {
    case diag::return_diagnostic_register:
      return echo_with(request, 0, out);  // no diagnostic bits are defined here
    case diag::clear_counters:
      cleared = counters;
      return echo_with(request, 0, out);
    case diag::clear_overrun_counter:
      cleared.bus_char_overruns = counters.bus_char_overruns;
      return echo_with(request, 0, out);
    default:
      return exception_pdu(kFunction, Exception::illegal_function, out);
  }
}

}  // namespace drivegate::modbus
