// Telnet (RFC 854 / 855) framing for a serial line carried over TCP, as RFC 2217 serial device
// servers speak it, and the COM-PORT-OPTION messages of RFC 2217 itself. Pure: bytes in, data and
// events out, no I/O, no clock, no logging.
//
// On the wire, data byte 0xFF (IAC) is doubled in both directions (RFC 854, "The Telnet
// command structure"); everything else after an IAC is a command: DO / DONT / WILL / WONT
// <option>, or a subnegotiation IAC SB <option> <payload> IAC SE, in whose payload 0xFF is
// doubled too.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drivegate/bytes.h"
#include "drivegate/line.h"

namespace drivegate::telnet {

// RFC 854 command codes.
inline constexpr std::uint8_t kIac = 255;
inline constexpr std::uint8_t kDont = 254;
inline constexpr std::uint8_t kDo = 253;
inline constexpr std::uint8_t kWont = 252;
inline constexpr std::uint8_t kWill = 251;
inline constexpr std::uint8_t kSb = 250;
inline constexpr std::uint8_t kSe = 240;

// Options.
inline constexpr std::uint8_t kBinary = 0;           // RFC 856: no CR / NUL stuffing
inline constexpr std::uint8_t kSuppressGoAhead = 3;  // RFC 858
inline constexpr std::uint8_t kComPortOption = 44;   // RFC 2217

// What the decoder found besides data, in the order it came.
struct Event {
  enum class Kind : std::uint8_t { negotiation, subnegotiation };
  Kind kind = Kind::negotiation;
  std::uint8_t verb = 0;  // negotiation: kDo, kDont, kWill or kWont
  std::uint8_t option = 0;
  Bytes payload;  // subnegotiation: the bytes between option and IAC SE, unescaped
  friend bool operator==(const Event&, const Event&) = default;
};

// Incremental: a command split across reads is completed by the next one.
class Decoder {
 public:
  // Appends the line data in `in` to `data` and the commands to `events`.
  void feed(ByteView in, Bytes& data, std::vector<Event>& events);

 private:
  enum class State : std::uint8_t { data, iac, verb, sb_option, sb_payload, sb_iac };
  State state_ = State::data;
  std::uint8_t verb_ = 0;
  Event sub_;
  // A subnegotiation longer than this is not one we understand: dropped, not grown forever.
  static constexpr std::size_t kMaxPayload = 64;
};

// `data` with every 0xFF doubled, appended to `out`.
void escape(ByteView data, Bytes& out);
// IAC <verb> <option>.
Bytes negotiation(std::uint8_t verb, std::uint8_t option);
// IAC SB <option> <payload, 0xFF doubled> IAC SE.
Bytes subnegotiation(std::uint8_t option, ByteView payload);

}  // namespace drivegate::telnet

namespace drivegate::rfc2217 {

// Client-to-server COM-PORT-OPTION commands (RFC 2217, "Com Port Configuration Commands"); the
// server answers each with the same code + 100 and the value it now uses.
enum class Command : std::uint8_t {
  set_baudrate = 1,  // 4 bytes, network order
  set_datasize = 2,  // 1 byte: 5..8
  set_parity = 3,    // 1 byte: 1 none, 2 odd, 3 even, 4 mark, 5 space
  set_stopsize = 4,  // 1 byte: 1 one, 2 two, 3 one and a half
  set_control = 5,   // 1 byte: 1 no flow control (outbound), ...
};
inline constexpr std::uint8_t kServerReplyOffset = 100;
inline constexpr std::uint8_t kNoFlowControl = 1;

// The settings a bus asks for, and how they are written in RFC 2217.
struct LineSettings {
  std::uint32_t baud = 9600;
  std::uint8_t data_bits = 8;
  Parity parity = Parity::none;
  std::uint8_t stop_bits = 1;
  friend bool operator==(const LineSettings&, const LineSettings&) = default;
};
std::uint8_t parity_code(Parity p);
std::uint8_t stop_code(std::uint8_t stop_bits);

// The whole request: SET-BAUDRATE, SET-DATASIZE, SET-PARITY, SET-STOPSIZE, SET-CONTROL (none),
// each its own subnegotiation.
Bytes configure(const LineSettings& s);

// What the server's answers say so far; each field set once its answer came.
struct ServerSettings {
  std::optional<std::uint32_t> baud;
  std::optional<std::uint8_t> data_bits;
  std::optional<std::uint8_t> parity;  // RFC 2217 code
  std::optional<std::uint8_t> stop;    // RFC 2217 code
  [[nodiscard]] bool complete() const { return baud && data_bits && parity && stop; }
};
// Takes one COM-PORT-OPTION subnegotiation payload from the server (code, value); false when it
// is not an answer to a configuration command (notifications and the like are ignored).
bool take_answer(ByteView payload, ServerSettings& s);
// Empty when the server uses what was asked; otherwise what differs, for the log.
std::string mismatch(const LineSettings& asked, const ServerSettings& got);

}  // namespace drivegate::rfc2217
