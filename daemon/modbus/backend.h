// What the Modbus TCP server asks of the gateway. The server owns framing, dispatch and
// connections; the backend owns the register image and the devices. Reads are synchronous (they
// are served from memory and never wait on a serial bus); writes complete later, when the device
// confirmed them or failed to. The daemon's backend is modbus/backend_switch.h: the gateway, its
// outcomes (gateway/outcome.h) answered as these exceptions.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>

#include "drivegate/point.h"  // Table: the four Modbus tables, one enum for every layer
#include "gateway/session.h"  // Session: who asks (dg_gateway_api, below this layer)

namespace drivegate::modbus {

// Modbus exception codes (Modbus Application Protocol V1.1b3, section 7). `none` = success.
enum class Exception : std::uint8_t {
  none = 0x00,
  illegal_function = 0x01,
  illegal_data_address = 0x02,
  illegal_data_value = 0x03,
  server_device_failure = 0x04,
  acknowledge = 0x05,
  server_device_busy = 0x06,
  gateway_path_unavailable = 0x0A,
  gateway_target_failed = 0x0B,
};

// Their names as the specification gives them (section 7), by code, for logs and MQTT results;
// "" for the codes it leaves unused or this server never sends.
inline constexpr std::array<std::string_view, 12> kExceptionNames = {
    "none",
    "illegal function",
    "illegal data address",
    "illegal data value",
    "server device failure",
    "acknowledge",
    "server device busy",
    "",
    "",
    "",
    "gateway path unavailable",
    "gateway target device failed to respond"};
constexpr std::string_view to_string(Exception e) {
  const auto code = static_cast<std::size_t>(e);
  return code < kExceptionNames.size() && !kExceptionNames[code].empty() ? kExceptionNames[code]
                                                                         : "unknown";
}

using WriteDone = std::function<void(Exception)>;
// A forwarded request's outcome (Backend::forward): none and the device's reply PDU as it came
// (valid during the call only), or the exception to answer instead.
using ForwardDone = std::function<void(Exception, std::span<const std::uint8_t> reply)>;

class Backend {
 public:
  virtual ~Backend() = default;
  // Fills `out` (one element per register, or one per bit with 0 / 1 for bit tables) with
  // `out.size()` values from `address`. Unknown unit: gateway_path_unavailable; any address in
  // the range unmapped: illegal_data_address.
  // `session` gives the word order of 32-bit values.
  virtual Exception read(const Session& session, std::uint8_t unit, Table table,
                         std::uint16_t address, std::span<std::uint16_t> out) = 0;
  // Validates synchronously (unknown unit, unmapped address, read-only, range) and returns the
  // exception at once if it fails; otherwise returns none and calls `done` exactly once later,
  // possibly after the connection that asked has gone (the server must tolerate that).
  // illegal_function is returned for one reason only: a point of the range needs more than
  // `session.access` (nothing was applied; the server counts and logs it as a denied write).
  // `values` are in `session.word_order`.
  // `values` is valid only during the call (it points into the server's scratch): copy what is
  // kept. `done` may be called from inside write(); the server defers its work to the event loop.
  virtual Exception write(const Session& session, std::uint8_t unit, Table table,
                          std::uint16_t address, std::span<const std::uint16_t> values,
                          WriteDone done) = 0;
  // A write the server refused itself, before any check the backend makes: a read-only
  // session's (MB-TCP-Security "Authorization": exception 01 at once). Told for the audit trail
  // (docs/audit.md), which records every write refused or not; `request` is the PDU.
  virtual void refused_write(const Session& /*session*/, std::uint8_t /*unit*/,
                             std::span<const std::uint8_t> /*request*/) {}
  // A broadcast write (serial address 0) a serial listener applied to no unit because it has
  // broadcast = false: told for the audit trail, with its PDU.
  virtual void refused_broadcast(const Session& /*session*/,
                                 std::span<const std::uint8_t> /*request*/) {}

  // Whether a device answers at `unit`. A serial line is shared with other slaves, so a serial
  // listener stays silent for a unit nobody here serves (MODBUS over Serial Line 2.2), where TCP
  // answers 0x0A.
  [[nodiscard]] virtual bool serves(std::uint8_t /*unit*/) const { return true; }

  // Pass-through: whether every request for `unit` is to be forwarded to its device as it is (a
  // modbus adapter device with passthrough = true) instead of served by read() and write().
  [[nodiscard]] virtual bool forwards(std::uint8_t /*unit*/) const { return false; }
  // Forwards `request` (a whole PDU, valid only during the call) to the device at `unit`. As
  // write(): an exception returned at once means nothing was sent, illegal_function for one
  // reason only (the function needs more than `session.access`); none means `done` is called
  // exactly once later.
  virtual Exception forward(const Session& /*session*/, std::uint8_t /*unit*/,
                            std::span<const std::uint8_t> /*request*/, ForwardDone /*done*/) {
    return Exception::gateway_path_unavailable;
  }
};

}  // namespace drivegate::modbus
