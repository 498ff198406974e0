// Pure codec of the Unicla eDrive RS-485 protocol (eDrive RS485 Interface V16, "RS485
// Communication Protocol"): 0x7E-delimited frames, 0x7D byte stuffing, an 8-byte header and a
// CRC-16/XMODEM sent high byte first. Bytes in, frames out: no I/O, no clock, no logging.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"
#include "drivegate/line.h"

namespace drivegate::unicla {

// "Communications Settings": 8 data bits, 1 stop bit, parity 0 (none), no flow control; "Baud
// Rate ... Default Value 19200". RS-485 half duplex with a driver-enable line: no echo.
inline constexpr LineDefaults kLine{19200, Parity::none, 8, 1, false};
// One character on that line (0.52 ms): the driver's timing choices are counted in these.
inline constexpr std::chrono::nanoseconds kCharacterTime = character_time(kLine);

// "Start and End of Frame": SOF and EOF are both 0x7E.
inline constexpr std::uint8_t kFlag = 0x7E;
// "Byte Stuffing/Unstuffing": escape byte 0x7D, the escaped byte is XORed with 0x20.
inline constexpr std::uint8_t kEscape = 0x7D;
inline constexpr std::uint8_t kEscapeXor = 0x20;
// "Message Structure": header of 8 bytes, CRC of 2.
inline constexpr std::size_t kHeaderSize = 8;
inline constexpr std::size_t kCrcSize = 2;
// "Payload Size" is one byte.
inline constexpr std::size_t kMaxPayload = 255;
// Longest frame on the wire: every body byte stuffed, plus SOF and EOF.
inline constexpr std::size_t kMaxWireSize = 2 * (kHeaderSize + kMaxPayload + kCrcSize) + 2;

// "Device Address": the master is always 0x00, 0xFF addresses every device; so a drive's own id is
// 1..254. "Configurable Parameters": Device ID, default 0x01.
inline constexpr std::uint8_t kMasterAddress = 0x00;
inline constexpr std::uint8_t kBroadcastAddress = 0xFF;
inline constexpr std::uint8_t kFirstDeviceId = 0x01;
inline constexpr std::uint8_t kLastDeviceId = 0xFE;
inline constexpr std::uint8_t kDefaultDeviceId = 0x01;

// "Commands": 0xC0 read, 0xC1 write.
enum class CommandByte : std::uint8_t { read = 0xC0, write = 0xC1 };

// "Message IDs".
enum class MessageId : std::uint8_t {
  status = 0x01,
  build_information = 0x02,
  running_limits = 0x03,
  set_run_state = 0xC0,
  acknowledge_faults = 0xC1,
};

struct Frame {
  std::uint8_t source = 0;
  std::uint8_t destination = 0;
  std::uint8_t command = 0;     // CommandByte, kept raw so that any value round-trips
  std::uint8_t message_id = 0;  // MessageId, raw for the same reason
  std::uint8_t sequence = 0;
  std::uint8_t reserved1 = 0;  // "Reserved: not used but must be set to 0"
  std::uint8_t reserved2 = 0;
  Bytes payload;

  friend bool operator==(const Frame&, const Frame&) = default;
};

// CRC-16/XMODEM (poly 0x1021, init 0), the document's calc_crc16 ("Cyclic Redundancy Check").
std::uint16_t crc16(ByteView data);

// Header + payload + CRC (high byte first), unstuffed, without flags.
Bytes frame_body(const Frame& f);
// SOF, the stuffed body, EOF.
Bytes wrap(ByteView body);
// The whole wire frame of `f`.
Bytes encode(const Frame& f);

// Incremental decoder over a receive buffer. Bytes before a SOF are dropped as bad_header; a
// good frame consumes SOF through EOF; a bad frame consumes up to (not including) the flag that
// ended it, since that flag may be the SOF of the next frame.
Decoded<Frame> decode(ByteView rx);

}  // namespace drivegate::unicla
