// What came of a read or a write the gateway was asked for, in the gateway's terms. Each
// northbound says it in its own words, in one place: the Modbus server as an exception code
// (modbus/modbus_exception.h), the MQTT northbound as a DCMD's result (mqtt/command_result.h).
//
// Header-only, in the CMake target dg_gateway_api with session.h (who asks).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>

namespace drivegate {

enum class Outcome : std::uint8_t {
  ok,              // a read served; a write applied and confirmed by the drive
  no_such_device,  // no device at that unit id (nor any gateway at all)
  // An address of the range not mapped; for a write also one that does not start a point, a
  // range that ends inside one, a point that is not writable or no write can carry (a string).
  no_such_point,
  // A point beyond the session's access level, and the only reason for it: checked before the
  // values, so nothing was applied and the driver never saw it.
  denied,
  // A value the point cannot take (outside its range, not encodable in its registers, NaN), or
  // one the drive judged invalid.
  invalid_value,
  busy,  // the device's write queue was full (kMaxQueuedWrites)
  // The drive refused it (judging the request, or in its reply), or the gateway did for it: a
  // run from a client that does not feed the PLC-loss failsafe while that is latched.
  refused,
  // Not confirmed by the drive, nor refused: it did not answer in time or no longer answers at
  // all (comm_lost), or the write was never sent (the gateway stopped or is shutting down, a stop
  // went before it, it waited past its deadline).
  no_response,
};

// Their names for the log, in enum order.
inline constexpr std::array<std::string_view, 8> kOutcomeNames = {
    "ok",   "no such device", "no such point", "denied", "invalid value",
    "busy", "refused",        "no response"};
constexpr std::string_view to_string(Outcome o) {
  return kOutcomeNames.at(static_cast<std::size_t>(o));
}

// How an accepted write tells its outcome later, exactly once (gateway/device.h says when).
using WriteDone = std::function<void(Outcome)>;
// Likewise for a request forwarded to a pass-through device (Device::forward): with ok, the
// slave's reply PDU as it came (valid during the call only), an exception reply included.
using ForwardDone = std::function<void(Outcome, std::span<const std::uint8_t> reply)>;

}  // namespace drivegate
