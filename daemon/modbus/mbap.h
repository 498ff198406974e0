// Pure MBAP framing for Modbus TCP: given the bytes received so far on one connection, says whether
// they start with a complete request (header, PDU, bytes consumed), a malformed header (the
// connection must be closed), or not enough bytes yet. No I/O, no clock, no logging.
//
// MBAP header (Modbus Messaging on TCP/IP Implementation Guide V1.0b, section 3.1.3):
//   transaction id (2) | protocol id (2, 0 = Modbus) | length (2: unit id + PDU) | unit id (1)
// all big-endian, followed by the PDU (function code + data).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <system_error>

namespace drivegate::modbus {

// Implementation Guide V1.0b, 3.1.3: the MBAP header is 7 bytes.
inline constexpr std::size_t kMbapHeaderSize = 7;
// Application Protocol V1.1b3, 4.1: a PDU is at most 253 bytes (256-byte RS-485 ADU minus address
// and CRC), so a TCP ADU is at most 260 bytes and the length field (unit id + PDU) at most 254.
inline constexpr std::size_t kMaxPduSize = 253;
inline constexpr std::uint16_t kMaxMbapLength = 254;
inline constexpr std::size_t kMaxAduSize = kMbapHeaderSize + kMaxPduSize;

struct MbapHeader {
  std::uint16_t transaction = 0;
  std::uint16_t protocol = 0;
  std::uint16_t length = 0;  // unit id + PDU bytes
  std::uint8_t unit = 0;
};

// Why a header is malformed.
enum class MbapError {
  bad_protocol_id = 1,  // protocol id != 0 (Implementation Guide 3.1.3: 0 = Modbus protocol)
  length_zero,          // the length counts the unit id, so 0 is impossible
  empty_pdu,            // length 1: a unit id and no function code; nothing to answer (README)
  length_too_long,      // length > 254: the PDU would exceed 253 bytes (Application Protocol 4.1)
};
const std::error_category& mbap_category();
std::error_code make_error_code(MbapError e);

struct MbapParse {
  enum class Status { good, bad, indeterminate };
  Status status = Status::indeterminate;
  MbapHeader header;                  // good: the whole header; bad: what was read of it
  std::span<const std::uint8_t> pdu;  // good: function code + data, 1..253 bytes
  std::size_t consumed = 0;           // good: header + PDU
  std::error_code error;              // bad: why
};

// Looks at the start of `buffer` only. A malformed header is reported as soon as the bytes that
// prove it have arrived (4 bytes for the protocol id, 6 for the length).
MbapParse parse_mbap(std::span<const std::uint8_t> buffer);

// Writes a 7-byte header for a response of `pdu_size` bytes into `out` (at least 7 bytes).
void put_mbap(std::span<std::uint8_t> out, std::uint16_t transaction, std::uint8_t unit,
              std::size_t pdu_size);

}  // namespace drivegate::modbus

template <>
struct std::is_error_code_enum<drivegate::modbus::MbapError> : std::true_type {};
