// FDC1 12-42 V DC compressor controller, protocol v2 (vendor document 003, "FDC1 12-42V DC
// COMMUNICATION PROTOCOL v2", read with specs/README.md section "fdc1 (003)"). Pure codec: bytes
// in, frames out.
//
// Every number in the document is DECIMAL: the speed frame "72 115 minH minL maxH maxL 85 x" with
// 2000..3000 rpm gives x = 10 only when read as decimal (0x48^0x73^0x07^0xD0^0x0B^0xB8^0x55 =
// 0x0A, specs README), and "115" is not a byte in hexadecimal. So 27 76 = 1B 4C, 72 80 = 48 50,
// 72 115 = 48 73, 85 = 55.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <variant>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"
#include "drivegate/line.h"

namespace drivegate::fdc1 {

// HARDWARE: "UART 1200 baud 1 start bit ... 8 bits of data ... no parity 1 stop bit", TTL with
// separate RxD (pin 1) and TxD (pin 6): no echo of the master's own bytes.
inline constexpr LineDefaults kLine{1200, Parity::none, 8, 1, false};
// One character on that line (8.33 ms): an 8-byte frame takes 67 ms, a 22-byte one 183 ms.
inline constexpr std::chrono::nanoseconds kCharacterTime = character_time(kLine);

// The protocol's timing (constants only: the codec itself keeps no time).
// OUTPUT: "Every 0'5 s, one of these ... sequences is sent".
inline constexpr std::chrono::milliseconds kStreamPeriod{500};
// INPUT, Programming speed, SLAVE MODE: "the motor will stop if no speed is received within 60s".
inline constexpr std::chrono::seconds kSlaveWatchdog{60};
// INPUT programming: "The whole sequence must be received within 1 second".
inline constexpr std::chrono::milliseconds kFrameWindow{1000};

// INPUT, both frames: "The speeds ... should be between 1500 and 3500 rpm".
inline constexpr std::uint16_t kMinRpm = 1500;
inline constexpr std::uint16_t kMaxRpm = 3500;

// OUTPUT: the controller's unsolicited status, 8 bytes every 0.5 s.
inline constexpr std::uint8_t kStatusHead0 = 27;  // OUTPUT, byte 1
inline constexpr std::uint8_t kStatusHead1 = 76;  // OUTPUT, byte 2
inline constexpr std::size_t kStatusSize = 8;     // OUTPUT: 6 data bytes + 2 checksums
// INPUT "Programming mode + parameters": 22 bytes, 72 80 ...; echoed with 27 80 ...
inline constexpr std::uint8_t kMasterHead0 = 72;   // INPUT, byte 1 of both input frames
inline constexpr std::uint8_t kProgramHead1 = 80;  // INPUT programming, byte 2
inline constexpr std::uint8_t kEchoHead0 = 27;     // INPUT programming: "(27 and 80)"
inline constexpr std::size_t kProgramSize = 22;    // INPUT programming: "22-byte sequences"
// INPUT "Programming speed": 8 bytes, 72 115 minH minL maxH maxL 85 x.
inline constexpr std::uint8_t kSpeedHead1 = 115;  // INPUT speed, byte 2
inline constexpr std::uint8_t kSpeedFixed = 85;   // INPUT speed, byte 7
inline constexpr std::size_t kSpeedSize = 8;      // INPUT speed: "8-byte sequence"

// Scales of the OUTPUT words.
inline constexpr double kCurrentScale = 3160.0;  // OUTPUT: INT = measured_current * 3160
inline constexpr double kRestartScale = 122.0;   // OUTPUT: TR = time_remaining * 122
// INPUT programming: every voltage is sent as 1187 * volts.
inline constexpr double kVoltScale = 1187.0;
// INPUT programming, special battery system: bytes 13..18 are 255.
inline constexpr std::uint16_t kUnusedLevel = 0xFFFF;

// One streamed status frame. b3 == 0 is the "motor OFF" form (alarm, time to restart), any
// other b3 the "motor ON" form (speed, current): OUTPUT, "the 3rd byte helps determine".
struct Status {
  bool motor_on = false;
  std::uint16_t rpm = 0;   // ON: SP1 * 256 + SP2
  std::uint8_t alarm = 0;  // OFF: A
  std::uint16_t word = 0;  // ON: current x 3160; OFF: seconds to restart x 122
  [[nodiscard]] double current_a() const { return motor_on ? word / kCurrentScale : 0.0; }
  [[nodiscard]] double restart_s() const { return motor_on ? 0.0 : word / kRestartScale; }
  friend bool operator==(const Status&, const Status&) = default;
};

// The 22-byte programming frame's fields (bytes 3..20). `levels` are bytes 9..20 as six words,
// 1187 x volts each: standard form cut_out_12V, cut_in_12V, cut_out_24V, cut_in_24V,
// cut_out_42V, cut_in_42V; special form cut_out, cut_in, 0xFFFF, 0xFFFF, 0xFFFF, nominal.
struct Program {
  std::uint16_t min_rpm = 0;
  std::uint16_t max_rpm = 0;
  std::uint8_t reserved = 0;  // byte 7: always 0
  std::uint8_t mode = 0;      // byte 8
  std::array<std::uint16_t, 6> levels{};
  friend bool operator==(const Program&, const Program&) = default;
};

// The 8-byte speed programming frame.
struct Speed {
  std::uint16_t min_rpm = 0;
  std::uint16_t max_rpm = 0;
  friend bool operator==(const Speed&, const Speed&) = default;
};

// What the controller sends: a status, or the echo of a programming frame.
struct Echo {
  Program program;
  friend bool operator==(const Echo&, const Echo&) = default;
};
using DeviceFrame = std::variant<Status, Echo>;
// What the master sends.
using MasterFrame = std::variant<Speed, Program>;

// Checksums.
// OUTPUT: checksum_odd = b1^b3^b5, checksum_even = b2^b4^b6; INPUT programming: the same over
// bytes 1..20. Both: XOR of the odd-numbered (1-based) and of the even-numbered bytes of `data`.
std::array<std::uint8_t, 2> xor_pair(ByteView data);
// INPUT speed: checksum = b1 ^ ... ^ b7.
std::uint8_t xor_all(ByteView data);

// Encoders (whole frames, checksums included).
Bytes encode_status(const Status& s);
Bytes encode_speed(const Speed& s);
Bytes encode_program(const Program& p);
// The controller's echo: the programming frame with bytes 1..2 replaced by 27 80 and every other
// byte, the checksums included, unchanged (INPUT programming, last bullet, read literally).
Bytes encode_echo(const Program& p);

// Incremental decoders over a receive buffer that starts where the last frame ended. `bad`
// consumes up to the next byte that could start a frame, so the caller resynchronises on the
// header. The echo is accepted whether its checksum was left as sent (over 72 80) or recomputed
// over 27 80.
Decoded<DeviceFrame> decode_device(ByteView rx);
Decoded<MasterFrame> decode_master(ByteView rx);

}  // namespace drivegate::fdc1
