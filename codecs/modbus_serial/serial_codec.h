// Modbus serial line codec: pure, bytes in, frames out. Both framings of the "MODBUS over Serial
// Line Specification and Implementation Guide V1.02" (here "Serial Line"), around the PDU of the
// "MODBUS Application Protocol Specification V1.1b3" (here "Application Protocol"):
//   RTU:   address, PDU, CRC-16 low byte first; a frame ends in 3.5 characters of silence
//          (Serial Line 2.5.1.1, 6.2.2).
//   ASCII: ':' then address, PDU and LRC as two hex characters each, then CR LF
//          (Serial Line 2.5.2.1, 6.2.1).
// A master (the modbus adapter's driver) encodes requests and decodes replies; a slave (its
// simulator, and the daemon's serial listeners) decodes requests and encodes replies. One codec
// for both ends of the line: the adapter plugin and the daemon link this library
// (dg_modbus_serial, in codecs/: below both, knowing neither). The decoders are incremental: they
// answer `incomplete` until a whole frame is in, so they work on a receive buffer that grows
// byte by byte.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"

namespace drivegate::modbus_serial {

enum class Framing : std::uint8_t { rtu, ascii };

// Address 0 is the broadcast, 1..247 are slaves (Serial Line 2.2).
inline constexpr std::uint8_t kBroadcast = 0;
inline constexpr std::uint8_t kMaxSlave = 247;
// A PDU is at most 253 bytes: function code and data (Application Protocol 4.1).
inline constexpr std::size_t kMaxPdu = 253;
// An RTU frame is the address, the PDU and the CRC (Serial Line 2.5.1.1): at least 4 bytes.
inline constexpr std::size_t kRtuOverhead = 3;
inline constexpr std::size_t kRtuMinFrame = 4;
// An exception reply's function code has its top bit set (Application Protocol 7).
inline constexpr std::uint8_t kExceptionBit = 0x80;
// Quantities one request may carry: 1..2000 coils or discrete inputs read (6.1, 6.2), 1..125
// registers read (6.3, 6.4), 1..123 registers written (6.12).
inline constexpr std::uint16_t kMaxReadBits = 2000;
inline constexpr std::uint16_t kMaxReadRegisters = 125;
inline constexpr std::uint16_t kMaxWriteRegisters = 123;

// Function codes the codec knows the lengths of (Application Protocol 6.x). A frame of any other
// is delimited by its CRC (decode_reply, decode_request); pass-through forwards none of them.
namespace fc {
inline constexpr std::uint8_t read_coils = 0x01;                // 6.1
inline constexpr std::uint8_t read_discrete_inputs = 0x02;      // 6.2
inline constexpr std::uint8_t read_holding_registers = 0x03;    // 6.3
inline constexpr std::uint8_t read_input_registers = 0x04;      // 6.4
inline constexpr std::uint8_t write_single_coil = 0x05;         // 6.5
inline constexpr std::uint8_t write_single_register = 0x06;     // 6.6
inline constexpr std::uint8_t read_exception_status = 0x07;     // 6.7 (serial line only)
inline constexpr std::uint8_t diagnostics = 0x08;               // 6.8 (serial line only)
inline constexpr std::uint8_t get_comm_event_counter = 0x0B;    // 6.9
inline constexpr std::uint8_t get_comm_event_log = 0x0C;        // 6.10
inline constexpr std::uint8_t write_multiple_coils = 0x0F;      // 6.11
inline constexpr std::uint8_t write_multiple_registers = 0x10;  // 6.12
inline constexpr std::uint8_t report_server_id = 0x11;          // 6.13
inline constexpr std::uint8_t read_file_record = 0x14;          // 6.14
inline constexpr std::uint8_t write_file_record = 0x15;         // 6.15
inline constexpr std::uint8_t mask_write_register = 0x16;       // 6.16
inline constexpr std::uint8_t read_write_registers = 0x17;      // 6.17
inline constexpr std::uint8_t read_fifo_queue = 0x18;           // 6.18
inline constexpr std::uint8_t encapsulated_interface = 0x2B;    // 6.19 / 6.21
}  // namespace fc

// RTU frames end in the CRC of drivegate/crc.h (Serial Line 6.2.2), low byte first.
// LRC of ASCII frames: the two's complement of the 8-bit sum of the address and PDU bytes
// (Serial Line 6.2.1, and its appendix "LRC Generation").
std::uint8_t lrc(ByteView data);

// One frame on the line: the slave address and the PDU.
struct Adu {
  std::uint8_t address = 0;
  Bytes pdu;  // function code, then data; 1..kMaxPdu bytes
};

// The frame for `address` and `pdu` in `framing`; empty when the PDU is empty or too long.
Bytes encode(Framing framing, std::uint8_t address, ByteView pdu);

// A user-defined function code (Application Protocol 5: 65..72, 100..110) whose request and reply
// have the layout of a public one: the "write without saving to EEPROM" 0x41 of several inverters
// is laid out as 0x06.
struct CodeLayout {
  std::uint8_t code = 0;
  std::uint8_t like = 0;
};
using CodeLayouts = std::span<const CodeLayout>;

// Whether `code` is a user-defined function code (Application Protocol 5).
constexpr bool user_defined_code(unsigned code) {
  return (code >= 65 && code <= 72) || (code >= 100 && code <= 110);
}

// A reply at the start of `rx` (a master's receive buffer). RTU: the length follows from the
// reply's function code and the byte counts in it (Application Protocol 6.x), a code of
// `layouts` (and its exception, code | 0x80) taken as its `like`; for a function the codec does not
// know, the frame ends where the bytes so far first carry a good CRC (the line's silence, which the
// bus engine does not report, would say the same; an echo can hold a good CRC before its end, so a
// master that sent a code of known layout names it). ASCII: the frame is what lies between ':'
// and CR LF. Bytes that cannot start a frame (RTU: a reserved address 248..255; ASCII: anything
// before ':') are `bad` with `bad_header`.
Decoded<Adu> decode_reply(Framing framing, ByteView rx, CodeLayouts layouts = {});

// A request at the start of `rx` (a slave's receive buffer), for the simulator. RTU lengths follow
// from the function code (request_length), a code of `layouts` taken as its `like`; an unknown
// function is delimited by its CRC.
Decoded<Adu> decode_request(Framing framing, ByteView rx, CodeLayouts layouts = {});

// Where the RTU frame at the start of `rx` ends for a slave that finds its end by its CRC alone,
// as decode_reply and decode_request do for a function of unknown length: the least size of at
// least kRtuMinFrame bytes, within the longest frame, whose last two bytes are the CRC of the
// bytes before them.
std::optional<std::size_t> crc_end(ByteView rx);

// How long a request PDU is, from its function code and the count in it (Application Protocol
// 6.x, the "Request" tables): where a slave that finds frame ends by length ends it.
struct RequestLength {
  enum class Status : std::uint8_t {
    known,       // `size` bytes, the function code included
    incomplete,  // the PDU ends before the count its length is read from
    // The codec does not know it: 0x08 (its data is any number of words, 6.8), 0x2B with an MEI
    // type other than 0x0E (6.19), and every function of no table.
    unknown,
  };
  Status status = Status::unknown;
  std::size_t size = 0;
};
RequestLength request_length(ByteView pdu);

// Whether the counts of a request PDU agree with each other, so that a slave finds the same end
// whichever of them it reads: the byte count and the quantity of 0x0F, 0x10 and 0x17 (6.11, 6.12,
// 6.17), the byte count and the sub-requests of 0x14 and 0x15 (6.14, 6.15: each of reference type
// 6, and 0x15's record data as long as its record length says). `pdu` is whole
// (request_length); a function with no such counts agrees.
bool request_counts_agree(ByteView pdu);

// The slave's exception reply PDU: function | 0x80, code (Application Protocol 7).
Bytes exception_pdu(std::uint8_t function, std::uint8_t code);

// The exception code of a reply PDU, or nothing when it is not an exception reply.
std::optional<std::uint8_t> exception_code(ByteView pdu);

}  // namespace drivegate::modbus_serial
