#include "diagnostics.h"

#include <algorithm>

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
  switch (sub) {
    case diag::return_diagnostic_register:
      return echo_with(request, 0, out);  // no diagnostic bits are defined here
    case diag::clear_counters:
      cleared = counters;
      return echo_with(request, 0, out);
    case diag::bus_message_count:
      return echo_with(request, counters.bus_messages - cleared.bus_messages, out);
    case diag::bus_comm_error_count:
      return echo_with(request, counters.bus_comm_errors - cleared.bus_comm_errors, out);
    case diag::bus_exception_error_count:
      return echo_with(request, counters.bus_exception_errors - cleared.bus_exception_errors, out);
    case diag::server_message_count:
      return echo_with(request, counters.server_messages - cleared.server_messages, out);
    case diag::server_no_response_count:
      return echo_with(request, counters.server_no_response - cleared.server_no_response, out);
    case diag::server_nak_count:
      return echo_with(request, counters.server_nak - cleared.server_nak, out);
    case diag::server_busy_count:
      return echo_with(request, counters.server_busy - cleared.server_busy, out);
    case diag::bus_char_overrun_count:
      return echo_with(request, counters.bus_char_overruns - cleared.bus_char_overruns, out);
    case diag::clear_overrun_counter:
      cleared.bus_char_overruns = counters.bus_char_overruns;
      return echo_with(request, 0, out);
    default:
      return exception_pdu(kFunction, Exception::illegal_function, out);
  }
}

}  // namespace drivegate::modbus
