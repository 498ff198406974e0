// ED3100 Modbus RTU codec: pure, bytes in, frames out (vendor document "communication material
// structure (RTU mode)", read with shared/specs/README.md section "ed3100").
//
// Master frames are standard Modbus RTU (functions 03, 06, 10). The drive's 03 reply is not:
// where a standard reply carries a byte count it echoes the 2-byte register address (document,
// "03H: read register content": 1F 03 00 06 10 88 AB D3). decode_reply() accepts that form and
// the standard one, telling them apart by CRC.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"

namespace drivegate::ed3100 {

// Function codes (document, "Function").
inline constexpr std::uint8_t kFnRead = 0x03;
inline constexpr std::uint8_t kFnWriteSingle = 0x06;
inline constexpr std::uint8_t kFnWriteMultiple = 0x10;
// Modbus exception replies set the top bit of the function code (Modbus application protocol
// 7; the ED3100 document is silent on exceptions).
inline constexpr std::uint8_t kExceptionBit = 0x80;
// Function 10 writes at most two registers (document, "10H: ... only continuously change two
// parameters").
inline constexpr std::size_t kMaxWriteWords = 2;
// Address 0 is the broadcast; 1..31 are drives (document, "Address").
inline constexpr std::uint8_t kBroadcast = 0x00;

// The CRC is Modbus RTU's: init FFFF, polynomial A001, sent low byte first (document, "RTU mode
// check code"; drivegate/crc.h).

// Master requests.
Bytes encode_read(std::uint8_t address, std::uint16_t reg, std::uint16_t count);
Bytes encode_write_single(std::uint8_t address, std::uint16_t reg, std::uint16_t value);
// 1..kMaxWriteWords values; anything else returns an empty frame.
Bytes encode_write_multiple(std::uint8_t address, std::uint16_t reg,
                            std::span<const std::uint16_t> values);

enum class ReadForm : std::uint8_t {
  document,  // addr 03 regHi regLo words.. CRC (the drive's own form)
  standard,  // addr 03 byteCount words.. CRC (Modbus application protocol 6.3)
};

// Slave replies (used by the simulator; the 06 reply is the request echoed, encode_write_single).
Bytes encode_read_reply(std::uint8_t address, std::uint16_t reg,
                        std::span<const std::uint16_t> words, ReadForm form);
Bytes encode_write_multiple_reply(std::uint8_t address, std::uint16_t reg, std::uint16_t count);
Bytes encode_exception(std::uint8_t address, std::uint8_t function, std::uint8_t code);

// A request as the drive sees it.
struct Request {
  std::uint8_t address = 0;
  std::uint8_t function = 0;
  std::uint16_t reg = 0;
  std::uint16_t count = 0;           // 03 and 10: the quantity field; 06: 1
  std::vector<std::uint16_t> words;  // 06: the value; 10: the values
};

// Requests are framed by their function code: 03 and 06 are 8 bytes, 10 is 9 + its byte count.
Decoded<Request> decode_request(ByteView rx);

// What the master expects back for the request it sent.
struct ReplyShape {
  std::uint8_t function = kFnRead;
  std::uint16_t reg = 0;    // the register the request named
  std::uint16_t words = 1;  // 03 only: the data words the reply carries
};

enum class ReplyKind : std::uint8_t { read_document, read_standard, write_echo, exception };

struct Reply {
  std::uint8_t address = 0;
  std::uint8_t function = 0;  // without the exception bit
  ReplyKind kind = ReplyKind::read_document;
  std::uint16_t reg = 0;             // read_document, write_echo (0 for read_standard)
  std::uint16_t value = 0;           // 06: the value echoed; 10: the quantity echoed
  std::vector<std::uint16_t> words;  // 03 data
  std::uint8_t exception = 0;        // exception code
};

// Decodes one reply of `shape` from the front of `rx`, of any address (the caller judges the
// address). bad + bad_header (consumed 1): rx[1] is neither the function nor its exception;
// bad + bad_checksum: every length the shape allows is present and none has a good CRC
// (consumed = the longest of them).
Decoded<Reply> decode_reply(ByteView rx, const ReplyShape& shape);

}  // namespace drivegate::ed3100
