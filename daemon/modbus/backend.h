// What the Modbus TCP server asks of the gateway. The server owns framing, dispatch and
// connections; the backend owns the register image and the devices. Reads are synchronous (they
// are served from memory and never wait on a serial bus); writes complete later, when the device
// confirmed them or failed to.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string_view>

#include "drivegate/point.h"  // Table: the four Modbus tables, one enum for every layer

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

// The exception's name as the specification gives it (section 7), for logs and MQTT results.
constexpr std::string_view to_string(Exception e) {
  switch (e) {
    case Exception::none:
      return "none";
    case Exception::illegal_function:
      return "illegal function";
    case Exception::illegal_data_address:
      return "illegal data address";
    case Exception::illegal_data_value:
      return "illegal data value";
    case Exception::server_device_failure:
      return "server device failure";
    case Exception::acknowledge:
      return "acknowledge";
    case Exception::server_device_busy:
      return "server device busy";
    case Exception::gateway_path_unavailable:
      return "gateway path unavailable";
    case Exception::gateway_target_failed:
      return "gateway target device failed to respond";
  }
  return "unknown";
}

// What a client may do (README, "Listeners and access"). Ordered: each level includes the ones
// below it.
enum class AccessLevel : std::uint8_t {
  read,      // reads only: every write function is answered 0x01
  operate,   // also the common command block: command, setpoint_rpm, heartbeat
  maintain,  // every writable point
};

// Their names in drivegate.toml and in the log, in enum order.
inline constexpr std::array<std::string_view, 3> kAccessLevelNames = {"read", "operate",
                                                                      "maintain"};
constexpr std::string_view to_string(AccessLevel a) {
  return kAccessLevelNames.at(static_cast<std::size_t>(a));
}

// How 32-bit values are laid over two registers for a client: big = high word first (the register
// map's order), little = low word first. Registers of 16 bits and bits are never reordered.
enum class WordOrder : std::uint8_t { big, little };
inline constexpr std::array<std::string_view, 2> kWordOrderNames = {"big", "little"};
constexpr std::string_view to_string(WordOrder w) {
  return kWordOrderNames.at(static_cast<std::size_t>(w));
}

// Who is asking: the connection's access level and word order (its listener's, or the role of its
// TLS client certificate). Passed with every read and write.
// The default may only read: a session gets more only from its listener or its certificate.
struct Session {
  AccessLevel access = AccessLevel::read;
  WordOrder word_order = WordOrder::big;
  // Whether this client's valid writes to the command block prove the PLC is there (feed the
  // PLC-loss failsafe, docs/safety.md). Every Modbus client's do; MQTT's only when configured.
  bool feeds_failsafe = true;
};

using WriteDone = std::function<void(Exception)>;

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
};

}  // namespace drivegate::modbus
