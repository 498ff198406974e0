#include "pdu.h"

#include <algorithm>
#include <utility>

#include "drivegate/bytes.h"

namespace drivegate::modbus {
namespace {

// Largest quantities per request (Application Protocol V1.1b3).
constexpr std::uint16_t kMaxReadBits = 0x07D0;        // 6.1 / 6.2: 1..2000 coils / inputs
constexpr std::uint16_t kMaxReadRegisters = 0x007D;   // 6.3 / 6.4: 1..125 registers
constexpr std::uint16_t kMaxWriteBits = 0x07B0;       // 6.11: 1..1968 coils
constexpr std::uint16_t kMaxWriteRegisters = 0x007B;  // 6.12: 1..123 registers
constexpr std::uint16_t kMaxRwRead = 0x007D;          // 6.17: read 1..125 registers
constexpr std::uint16_t kMaxRwWrite = 0x0079;         // 6.17: write 1..121 registers
// 6.5: a single coil is written with FF 00 (ON) or 00 00 (OFF); any other value is 0x03.
constexpr std::uint16_t kCoilOn = 0xFF00;
constexpr std::uint16_t kCoilOff = 0x0000;

void put16(std::span<std::uint8_t> b, std::size_t at, std::uint16_t v) {
  b[at] = static_cast<std::uint8_t>(v >> 8);
  b[at + 1] = static_cast<std::uint8_t>(v);
}
// Every function: "Starting Address + Quantity" must stay within the 65536-entry table, else 0x02.
constexpr bool overflows(std::uint16_t address, std::size_t count) {
  return std::size_t{address} + count > 0x10000;
}

using Result = Dispatcher::Result;
Result reply(std::size_t size) {
  return {Result::Status::reply, size};
}
Result fail(std::uint8_t function, Exception code, std::span<std::uint8_t> out) {
  return reply(exception_pdu(function, code, out));
}

}  // namespace

bool may_write(std::uint8_t function) {
  switch (static_cast<Function>(function)) {
    case Function::write_single_coil:
    case Function::write_single_register:
    case Function::write_multiple_coils:
    case Function::write_multiple_registers:
    case Function::read_write_registers:
      return true;
    default:
      return false;
  }
}

std::size_t exception_pdu(std::uint8_t function, Exception code, std::span<std::uint8_t> out) {
  out[0] = static_cast<std::uint8_t>(function | 0x80);  // section 7: function code + 0x80
  out[1] = static_cast<std::uint8_t>(code);
  return 2;
}

Dispatcher::Dispatcher(Backend& backend, DeviceIdentity identity)
    : backend_(backend),
      objects_{std::move(identity.vendor), std::move(identity.product),
               std::move(identity.version)} {
  // 6.21: each object must fit one response with the 7 header bytes and its own id and length
  // bytes beside it (253 - 9 = 244). Longer strings are cut (README).
  for (auto& s : objects_) {
    if (s.size() > kMaxPduSize - 9) s.resize(kMaxPduSize - 9);
  }
}

Result Dispatcher::handle(const Session& session, std::uint8_t unit,
                          std::span<const std::uint8_t> request, std::span<std::uint8_t> out,
                          WriteDone done) {
  session_ = &session;
  const std::uint8_t fc = request[0];
  // Modbus/TCP Security (MB-TCP-Security v21, "Authorization"): a request the client's role does
  // not allow is answered with exception 01. A read-only client may not write at all, so its
  // writes are refused before any other check and never reach the backend.
  if (session.access == AccessLevel::read && may_write(fc)) {
    backend_.refused_write(session, unit, request);
    Result r = fail(fc, Exception::illegal_function, out);
    r.denied = true;
    return r;
  }
  switch (static_cast<Function>(fc)) {
    case Function::read_coils:
      return read_bits(unit, Table::coil, request, out);
    case Function::read_discrete_inputs:
      return read_bits(unit, Table::discrete, request, out);
    case Function::read_holding_registers:
      return read_registers(unit, Table::holding, request, out);
    case Function::read_input_registers:
      return read_registers(unit, Table::input, request, out);
    case Function::write_single_coil:
      return write_single_coil(unit, request, out, std::move(done));
    case Function::write_single_register:
      return write_single_register(unit, request, out, std::move(done));
    case Function::write_multiple_coils:
      return write_multiple_coils(unit, request, out, std::move(done));
    case Function::write_multiple_registers:
      return write_multiple_registers(unit, request, out, std::move(done));
    case Function::read_write_registers:
      return read_write_registers(unit, request, out, std::move(done));
    case Function::encapsulated_interface:
      return device_identification(request, out);
  }
  return fail(fc, Exception::illegal_function, out);  // 7: code 01, function not supported
}

Result Dispatcher::forward(const Session& session, std::uint8_t unit,
                           std::span<const std::uint8_t> request, std::span<std::uint8_t> out,
                           ForwardDone done) {
  const Exception e = backend_.forward(session, unit, request, std::move(done));
  if (e == Exception::none) return {Result::Status::pending, 0};
  Result r = fail(request[0], e, out);
  r.denied = e == Exception::illegal_function;  // Backend::forward: only for the access level
  return r;
}

// 6.1 / 6.2: fc | start (2) | quantity (2) -> fc | byte count | bits, LSB of byte 0 = start.
Result Dispatcher::read_bits(std::uint8_t unit, Table table, std::span<const std::uint8_t> request,
                             std::span<std::uint8_t> out) {
  const std::uint8_t fc = request[0];
  if (request.size() != 5) return fail(fc, Exception::illegal_data_value, out);
  const std::uint16_t address = be16_at(request, 1);
  const std::uint16_t count = be16_at(request, 3);
  if (count < 1 || count > kMaxReadBits) return fail(fc, Exception::illegal_data_value, out);
  if (overflows(address, count)) return fail(fc, Exception::illegal_data_address, out);
  const std::span<std::uint16_t> bits(scratch_.data(), count);
  if (auto e = backend_.read(*session_, unit, table, address, bits); e != Exception::none) {
    return fail(fc, e, out);
  }
  const std::size_t bytes = (count + 7u) / 8u;
  out[0] = fc;
  out[1] = static_cast<std::uint8_t>(bytes);
  std::fill_n(out.begin() + 2, bytes, std::uint8_t{0});
  for (std::size_t i = 0; i < count; ++i) {
    if (bits[i] != 0) out[2 + i / 8] = static_cast<std::uint8_t>(out[2 + i / 8] | (1u << (i % 8)));
  }
  return reply(2 + bytes);
}

// 6.3 / 6.4: fc | start (2) | quantity (2) -> fc | byte count | registers, high byte first.
Result Dispatcher::read_registers(std::uint8_t unit, Table table,
                                  std::span<const std::uint8_t> request,
                                  std::span<std::uint8_t> out) {
  const std::uint8_t fc = request[0];
  if (request.size() != 5) return fail(fc, Exception::illegal_data_value, out);
  const std::uint16_t address = be16_at(request, 1);
  const std::uint16_t count = be16_at(request, 3);
  if (count < 1 || count > kMaxReadRegisters) return fail(fc, Exception::illegal_data_value, out);
  if (overflows(address, count)) return fail(fc, Exception::illegal_data_address, out);
  return reply(read_registers_response(unit, table, address, count, fc, out));
}

std::size_t Dispatcher::read_registers_response(std::uint8_t unit, Table table,
                                                std::uint16_t address, std::uint16_t count,
                                                std::uint8_t function,
                                                std::span<std::uint8_t> out) {
  const std::span<std::uint16_t> regs(scratch_.data(), count);
  if (auto e = backend_.read(*session_, unit, table, address, regs); e != Exception::none) {
    return exception_pdu(function, e, out);
  }
  out[0] = function;
  out[1] = static_cast<std::uint8_t>(2 * count);
  for (std::size_t i = 0; i < count; ++i) put16(out, 2 + 2 * i, regs[i]);
  return 2 + 2 * std::size_t{count};
}

Result Dispatcher::start_write(std::uint8_t unit, Table table, std::uint16_t address,
                               std::size_t count, std::span<std::uint8_t> out,
                               std::uint8_t function, WriteDone done) {
  const std::span<const std::uint16_t> values(scratch_.data(), count);
  if (auto e = backend_.write(*session_, unit, table, address, values, std::move(done));
      e != Exception::none) {
    Result r = fail(function, e, out);
    r.denied = e == Exception::illegal_function;  // backend.h: only for a denied access level
    return r;
  }
  return {Result::Status::pending, 0};
}

// 6.5: fc | address (2) | FF00 or 0000 -> echo of the request.
Result Dispatcher::write_single_coil(std::uint8_t unit, std::span<const std::uint8_t> request,
                                     std::span<std::uint8_t> out, WriteDone done) {
  const std::uint8_t fc = request[0];
  if (request.size() != 5) return fail(fc, Exception::illegal_data_value, out);
  const std::uint16_t value = be16_at(request, 3);
  if (value != kCoilOn && value != kCoilOff) return fail(fc, Exception::illegal_data_value, out);
  scratch_[0] = value == kCoilOn ? 1 : 0;
  return start_write(unit, Table::coil, be16_at(request, 1), 1, out, fc, std::move(done));
}

// 6.6: fc | address (2) | value (2) -> echo of the request.
Result Dispatcher::write_single_register(std::uint8_t unit, std::span<const std::uint8_t> request,
                                         std::span<std::uint8_t> out, WriteDone done) {
  const std::uint8_t fc = request[0];
  if (request.size() != 5) return fail(fc, Exception::illegal_data_value, out);
  scratch_[0] = be16_at(request, 3);
  return start_write(unit, Table::holding, be16_at(request, 1), 1, out, fc, std::move(done));
}

// 6.11: fc | start (2) | quantity (2) | byte count = ceil(N / 8) | bits -> fc | start | quantity.
Result Dispatcher::write_multiple_coils(std::uint8_t unit, std::span<const std::uint8_t> request,
                                        std::span<std::uint8_t> out, WriteDone done) {
  const std::uint8_t fc = request[0];
  if (request.size() < 6) return fail(fc, Exception::illegal_data_value, out);
  const std::uint16_t address = be16_at(request, 1);
  const std::uint16_t count = be16_at(request, 3);
  const std::size_t bytes = request[5];
  if (count < 1 || count > kMaxWriteBits || bytes != (count + 7u) / 8u ||
      request.size() != 6 + bytes) {
    return fail(fc, Exception::illegal_data_value, out);
  }
  if (overflows(address, count)) return fail(fc, Exception::illegal_data_address, out);
  for (std::size_t i = 0; i < count; ++i) scratch_[i] = (request[6 + i / 8] >> (i % 8)) & 1u;
  return start_write(unit, Table::coil, address, count, out, fc, std::move(done));
}

// 6.12: fc | start (2) | quantity (2) | byte count = 2N | registers -> fc | start | quantity.
Result Dispatcher::write_multiple_registers(std::uint8_t unit,
                                            std::span<const std::uint8_t> request,
                                            std::span<std::uint8_t> out, WriteDone done) {
  const std::uint8_t fc = request[0];
  if (request.size() < 6) return fail(fc, Exception::illegal_data_value, out);
  const std::uint16_t address = be16_at(request, 1);
  const std::uint16_t count = be16_at(request, 3);
  const std::size_t bytes = request[5];
  if (count < 1 || count > kMaxWriteRegisters || bytes != 2u * count ||
      request.size() != 6 + bytes) {
    return fail(fc, Exception::illegal_data_value, out);
  }
  if (overflows(address, count)) return fail(fc, Exception::illegal_data_address, out);
  for (std::size_t i = 0; i < count; ++i) scratch_[i] = be16_at(request, 6 + 2 * i);
  return start_write(unit, Table::holding, address, count, out, fc, std::move(done));
}

// 6.17: fc | read start (2) | read quantity (2) | write start (2) | write quantity (2) |
// byte count = 2 x write quantity | registers -> fc | byte count | read registers. The write is
// performed before the read, but a read that cannot be served must not leave its write behind
// (the client sees an exception and expects nothing to have changed): the read range is tried
// first, and its exception answers the request without any write.
Result Dispatcher::read_write_registers(std::uint8_t unit, std::span<const std::uint8_t> request,
                                        std::span<std::uint8_t> out, WriteDone done) {
  const std::uint8_t fc = request[0];
  if (request.size() < 10) return fail(fc, Exception::illegal_data_value, out);
  const std::uint16_t read_address = be16_at(request, 1);
  const std::uint16_t read_count = be16_at(request, 3);
  const std::uint16_t write_address = be16_at(request, 5);
  const std::uint16_t write_count = be16_at(request, 7);
  const std::size_t bytes = request[9];
  if (read_count < 1 || read_count > kMaxRwRead || write_count < 1 || write_count > kMaxRwWrite ||
      bytes != 2u * write_count || request.size() != 10 + bytes) {
    return fail(fc, Exception::illegal_data_value, out);
  }
  if (overflows(read_address, read_count) || overflows(write_address, write_count)) {
    return fail(fc, Exception::illegal_data_address, out);
  }
  // The same Backend::read that builds the response in complete(), so "readable" has one
  // definition. It reads into the scratch past the write values (scratch_[0, kMaxRwWrite)), so
  // neither clobbers the other whatever their order; what it reads is discarded (the response
  // reads again, after the write).
  static_assert(kMaxRwWrite + kMaxRwRead <= std::tuple_size_v<decltype(scratch_)>);
  const std::span<std::uint16_t> probe(scratch_.data() + kMaxRwWrite, read_count);
  if (auto e = backend_.read(*session_, unit, Table::holding, read_address, probe);
      e != Exception::none) {
    return fail(fc, e, out);
  }
  for (std::size_t i = 0; i < write_count; ++i) scratch_[i] = be16_at(request, 10 + 2 * i);
  return start_write(unit, Table::holding, write_address, write_count, out, fc, std::move(done));
}

std::size_t Dispatcher::complete(const Session& session, std::uint8_t unit,
                                 std::span<const std::uint8_t> request, Exception result,
                                 std::span<std::uint8_t> out) {
  session_ = &session;
  const std::uint8_t fc = request[0];
  if (result != Exception::none) return exception_pdu(fc, result, out);
  switch (static_cast<Function>(fc)) {
    case Function::write_single_coil:
    case Function::write_single_register:
    case Function::write_multiple_coils:
    case Function::write_multiple_registers:
      // 6.5 / 6.6: the response echoes the request; 6.11 / 6.12: fc, start, quantity.
      std::copy_n(request.begin(), 5, out.begin());
      return 5;
    case Function::read_write_registers:
      return read_registers_response(unit, Table::holding, be16_at(request, 1), be16_at(request, 3),
                                     fc, out);
    default:
      return exception_pdu(fc, Exception::server_device_failure, out);  // not a write: a bug
  }
}

}  // namespace drivegate::modbus
