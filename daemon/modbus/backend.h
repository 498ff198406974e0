// What the Modbus TCP server asks of the gateway. The server owns framing, dispatch and
// connections; the backend owns the register image and the devices. Reads are synchronous (they
// are served from memory and never wait on a serial bus); writes complete later, when the device
// confirmed them or failed to.
#pragma once

#include <cstdint>
#include <functional>
#include <span>

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

enum class RegisterTable : std::uint8_t {
  coils,
  discrete_inputs,
  input_registers,
  holding_registers
};

using WriteDone = std::function<void(Exception)>;

class Backend {
 public:
  virtual ~Backend() = default;
  // Fills `out` (one element per register, or one per bit with 0 / 1 for bit tables) with
  // `out.size()` values from `address`. Unknown unit: gateway_path_unavailable; any address in
  // the range unmapped: illegal_data_address.
  virtual Exception read(std::uint8_t unit, RegisterTable table, std::uint16_t address,
                         std::span<std::uint16_t> out) = 0;
  // Validates synchronously (unknown unit, unmapped address, read-only, range) and returns the
  // exception at once if it fails; otherwise returns none and calls `done` exactly once later,
  // possibly after the connection that asked has gone (the server must tolerate that).
  // `values` is valid only during the call (it points into the server's scratch): copy what is
  // kept. `done` may be called from inside write(); the server defers its work to the event loop.
  virtual Exception write(std::uint8_t unit, RegisterTable table, std::uint16_t address,
                          std::span<const std::uint16_t> values, WriteDone done) = 0;
};

}  // namespace drivegate::modbus
