// Nidec washer inverter bus protocol (customer Elaraby, spec V07): the pure codec. Bytes in,
// frames out; no I/O, no clock, no logging. Section numbers refer to the vendor document
// /work/shared/specs/000_d76a0d0d29a4b4f1.txt as read by /work/shared/specs/README.md.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"
#include "drivegate/line.h"

namespace drivegate::nidec {

// Section 3: 4800 baud, 8 information bits, odd parity, one stop bit; section 2: one wire, half
// duplex, so the master hears its own bytes.
inline constexpr LineDefaults kLine{
    .baud = 4800, .parity = Parity::odd, .data_bits = 8, .stop_bits = 1, .echo = true};

inline constexpr std::uint8_t kHeader = 0xA5;      // 4.1 / 4.2: 10100101
inline constexpr std::uint8_t kNackHeader = 0x5A;  // 4.2 / 5.16: 01011010 = NACK
inline constexpr std::size_t kRequestSize = 11;    // 4.1: fixed 11 bytes, checksum included
inline constexpr std::size_t kReplySize = 7;       // 4.2: fixed 7 bytes, checksum included
inline constexpr std::size_t kFctReplySize = 13;   // 5.15: the FCT ACK is the one exception
inline constexpr std::size_t kRequestData = 8;     // 4.1: bytes 3..10
inline constexpr std::size_t kMaxReplyData = kFctReplySize - 3;

// Section 5, "TYPES OF FRAME". Clutching 0x19 (5.12) was removed in V07 and is not offered.
enum class Mode : std::uint8_t {
  ping = 0x02,               // 5.1
  request = 0x05,            // 5.2
  cw = 0x09,                 // 5.3
  ccw = 0x0B,                // 5.4
  agitation = 0x0C,          // 5.5
  spin = 0x0D,               // 5.6
  forced_brake = 0x1B,       // 5.13
  free_shaft_spin = 0x1D,    // 5.14
  stop = 0x27,               // 5.7
  brake = 0x29,              // 5.8
  voltage_detection = 0x2B,  // 5.9
  weight_detection = 0x2C,   // 5.10
  fabric_detection = 0x2D,   // 5.11
  fct_test = 0x66,           // 5.15
};

// True for the modes of spec V07 (0x19 is not one).
bool is_v07_mode(std::uint8_t mode);

// XOR of every byte given (4.1 / 4.2: "A XOR of all frame bytes", i.e. those before it).
std::uint8_t xor_of(ByteView bytes);

// Master -> inverter (4.1): A5 MODE d1..d8 X.
struct Request {
  Mode mode = Mode::request;
  std::array<std::uint8_t, kRequestData> data{};
  friend bool operator==(const Request&, const Request&) = default;
};

Bytes encode(const Request& r);

// Agitation times (5.5), each one byte in 100 ms units.
struct AgitationTiming {
  std::uint8_t accel = 0;
  std::uint8_t decel = 0;
  std::uint8_t cw_on = 0;
  std::uint8_t cw_off = 0;
  std::uint8_t ccw_on = 0;
  std::uint8_t ccw_off = 0;
  friend bool operator==(const AgitationTiming&, const AgitationTiming&) = default;
};

Request make_bare(Mode mode);  // request, stop, brake, voltage/weight/fabric detection
Request make_ping(std::uint8_t platform, std::uint16_t empty_raw_weight);  // 5.1
// cw (5.3), ccw (5.4), spin (5.6), free_shaft_spin (5.14): speed, then accel in 100 ms units.
Request make_run(Mode mode, std::uint16_t rpm, std::uint16_t accel_100ms);
Request make_agitation(std::uint16_t rpm, const AgitationTiming& t);  // 5.5
Request make_forced_brake(bool enable);                               // 5.13
Request make_fct();                                                   // 5.15

// Inverter -> master (4.2): A5 MODE e1..e4 X (e1..e10 for FCT), or a NACK (5.16).
struct Reply {
  bool nack = false;
  Mode mode = Mode::request;  // meaningless for a NACK
  std::array<std::uint8_t, kMaxReplyData> data{};
  std::uint8_t size = 0;  // data bytes: 4, or 10 for FCT
  friend bool operator==(const Reply&, const Reply&) = default;

  [[nodiscard]] std::uint8_t error() const { return data[0]; }
  // 4.2 / section 5: multi-byte fields are high byte first.
  [[nodiscard]] std::uint16_t u16(std::size_t i) const { return be16(data[i], data[i + 1]); }
};

Bytes encode(const Reply& r);
Bytes encode_reply(Mode mode, std::array<std::uint8_t, 4> data);
Bytes encode_fct_reply(std::array<std::uint8_t, kMaxReplyData> data);
Bytes encode_nack();  // 5.16: 5A 00 FF 00 FF 00 5A

// Incremental decoders over a receive buffer that starts at a frame boundary (or at noise).
// A frame-shaped run with a bad XOR answers `bad` / bad_checksum and consumes only up to the
// next frame start inside it (A5, or 5A too for decode_reply), or the whole run when there is
// none, so that a good frame which began inside the damaged one is still found.
Decoded<Reply> decode_reply(ByteView rx);      // master side
Decoded<Request> decode_request(ByteView rx);  // inverter side (the simulator)

}  // namespace drivegate::nidec
