// How the Modbus server says each of the gateway's outcomes: the exception code of its response
// (Modbus Application Protocol Specification V1.1b3, section 7, "MODBUS Exception Responses").
// One code per outcome and one outcome per code, so that a client reads from the code alone what
// happened, and the codes are those clients got before the gateway had outcomes of its own.
// The server's backend (backend_switch.h) answers with it and `drivegate write` cites it;
// tests/modbus/outcome_test.cpp holds it to the table, and mqtt/command_result.h, which names the
// same codes for DCMDs, to it.
#pragma once

#include "gateway/outcome.h"
#include "modbus/backend.h"

namespace drivegate {

constexpr modbus::Exception modbus_exception(Outcome o) {
  using modbus::Exception;
  switch (o) {
    case Outcome::ok:
      return Exception::none;
    case Outcome::no_such_device:
      return Exception::gateway_path_unavailable;  // 0x0A: no path to that unit id
    case Outcome::no_such_point:
      return Exception::illegal_data_address;  // 0x02
    case Outcome::denied:
      // 0x01, and modbus::Backend keeps it for this alone: the server counts and logs it as a
      // denied write (writes_denied), as it does the writes of a read-only listener.
      return Exception::illegal_function;
    case Outcome::invalid_value:
      return Exception::illegal_data_value;  // 0x03
    case Outcome::busy:
      return Exception::server_device_busy;  // 0x06: the client may try again later
    case Outcome::refused:
      return Exception::server_device_failure;  // 0x04: the action could not be performed
    case Outcome::no_response:
      return Exception::gateway_target_failed;  // 0x0B: the target device did not respond
  }
  return Exception::server_device_failure;  // not an outcome at all
}

}  // namespace drivegate
