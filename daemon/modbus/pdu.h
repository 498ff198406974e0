// Pure dispatch of one Modbus request PDU against a Backend: decodes the function, checks every
// quantity, byte count and address range of the Modbus Application Protocol V1.1b3, calls the
// backend and builds the response PDU (or the exception PDU, section 7) into a caller-owned
// buffer. No I/O, no clock, no logging. Writes are asynchronous: handle() starts them and
// complete() builds their response once the backend's `done` has fired.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "backend.h"
#include "mbap.h"

namespace drivegate::modbus {

// Function codes served (Application Protocol V1.1b3, section 5.1 / 6.x).
enum class Function : std::uint8_t {
  read_coils = 0x01,                // 6.1
  read_discrete_inputs = 0x02,      // 6.2
  read_holding_registers = 0x03,    // 6.3
  read_input_registers = 0x04,      // 6.4
  write_single_coil = 0x05,         // 6.5
  write_single_register = 0x06,     // 6.6
  write_multiple_coils = 0x0F,      // 6.11
  write_multiple_registers = 0x10,  // 6.12
  read_write_registers = 0x17,      // 6.17
  encapsulated_interface = 0x2B,    // 6.19 / 6.21 (MEI type 0x0E: read device identification)
};

// Objects of the basic device identification (6.21): VendorName, ProductCode, MajorMinorRevision.
struct DeviceIdentity {
  std::string vendor = "drivegate";
  std::string product = "drivegate";
  std::string version;
};

// True for the functions whose handling may call Backend::write (and so may answer later).
bool may_write(std::uint8_t function);

class Dispatcher {
 public:
  struct Result {
    enum class Status {
      reply,   // `size` bytes of response (or exception) PDU are in `out`
      pending  // a backend write was started; its `done` will fire (maybe already has)
    };
    Status status = Status::reply;
    std::size_t size = 0;
    bool denied = false;  // the reply is exception 01 to a write beyond the session's access
  };

  Dispatcher(Backend& backend, DeviceIdentity identity);

  // `request` is the PDU (function code + data, 1..253 bytes). `out` must hold kMaxPduSize bytes.
  // `done` is handed to Backend::write when the function writes; it is not used otherwise.
  // `session` is handed to the backend with every read and write, and refuses every write
  // function at once (exception 01, `denied`) when its access level is read.
  Result handle(const Session& session, std::uint8_t unit, std::span<const std::uint8_t> request,
                std::span<std::uint8_t> out, WriteDone done);

  // Pass-through (Backend::forwards): every request for such a unit goes to forward() instead of
  // handle(), whatever its function, and is answered with the device's own reply, later.
  [[nodiscard]] bool forwards(std::uint8_t unit) const { return backend_.forwards(unit); }
  // Whether a request is answered later (a write, or anything for a pass-through unit): such a
  // request needs one of its host's pending slots, and waits at their cap.
  [[nodiscard]] bool answers_later(std::uint8_t unit, std::uint8_t function) const {
    return may_write(function) || forwards(unit);
  }
  // Starts forwarding `request`: `pending` (then `done` fires, maybe already has), or the
  // exception reply when it was refused at once (`denied` when beyond the session's access).
  Result forward(const Session& session, std::uint8_t unit, std::span<const std::uint8_t> request,
                 std::span<std::uint8_t> out, ForwardDone done);

  // The response to a write request that handle() left pending, once its `done` reported
  // `result`: the exception, or the function's normal response (for 0x17, the read that follows
  // the write). Returns the PDU size written to `out`.
  std::size_t complete(const Session& session, std::uint8_t unit,
                       std::span<const std::uint8_t> request, Exception result,
                       std::span<std::uint8_t> out);

 private:
  Result read_bits(std::uint8_t unit, Table table, std::span<const std::uint8_t> request,
                   std::span<std::uint8_t> out);
  Result read_registers(std::uint8_t unit, Table table, std::span<const std::uint8_t> request,
                        std::span<std::uint8_t> out);
  Result write_single_coil(std::uint8_t unit, std::span<const std::uint8_t> request,
                           std::span<std::uint8_t> out, WriteDone done);
  Result write_single_register(std::uint8_t unit, std::span<const std::uint8_t> request,
                               std::span<std::uint8_t> out, WriteDone done);
  Result write_multiple_coils(std::uint8_t unit, std::span<const std::uint8_t> request,
                              std::span<std::uint8_t> out, WriteDone done);
  Result write_multiple_registers(std::uint8_t unit, std::span<const std::uint8_t> request,
                                  std::span<std::uint8_t> out, WriteDone done);
  Result read_write_registers(std::uint8_t unit, std::span<const std::uint8_t> request,
                              std::span<std::uint8_t> out, WriteDone done);
  Result device_identification(std::span<const std::uint8_t> request, std::span<std::uint8_t> out);
  Result start_write(std::uint8_t unit, Table table, std::uint16_t address, std::size_t count,
                     std::span<std::uint8_t> out, std::uint8_t function, WriteDone done);
  std::size_t read_registers_response(std::uint8_t unit, Table table, std::uint16_t address,
                                      std::uint16_t count, std::uint8_t function,
                                      std::span<std::uint8_t> out);

  Backend& backend_;
  // The session of the call in progress (handle / complete), for the backend calls below it. The
  // dispatcher is shared by a server's connections and never re-entered, like scratch_.
  const Session* session_ = nullptr;
  std::array<std::string, 3> objects_;  // 6.21 object ids 0x00..0x02
  // Register / bit values between the wire and the backend: 2000 = the largest quantity of any
  // function (read coils / discrete inputs, 6.1 / 6.2).
  std::array<std::uint16_t, 2000> scratch_{};
};

// Writes the exception PDU (Application Protocol section 7: function | 0x80, code). Returns 2.
std::size_t exception_pdu(std::uint8_t function, Exception code, std::span<std::uint8_t> out);

}  // namespace drivegate::modbus
