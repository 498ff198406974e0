// Pure codec of the mdriver-2400 compressor motor driver protocol (vendor document
// 002_3cbe8a9e68a52108.txt, "モータドライバの通信仕様"; reading in shared/specs/README.md).
//
//   src dst cmd n data[n+1] cs     sum of ALL bytes, cs included, = 0x55 (mod 256)
//
// Bytes in, frames out: no I/O, no clock, no logging.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"
#include "drivegate/line.h"

namespace drivegate::mdriver {

// Section 1 No.1..3: full-duplex UART, 2400 bps, 1 start bit, 8 data bits, no parity, 1 stop bit
// (so no echo of our own bytes).
inline constexpr LineDefaults kLine{2400, Parity::none, 8, 1, false};
// One character on that line (4.17 ms): the driver's timing choices are counted in these.
inline constexpr std::chrono::nanoseconds kCharacterTime = character_time(kLine);

// Section 2: "checksum (D0~D6 Total 55)": the sum of every byte of the frame is 0x55.
inline constexpr std::uint8_t kChecksumTotal = 0x55;
// Section 2: D0 src, D1 dst, D2 command, D3 data length - 1, then data, then the checksum.
inline constexpr std::size_t kHeaderSize = 4;
inline constexpr std::size_t kOverhead = kHeaderSize + 1;
// Section 1 No.6: at most 15 bytes a frame (address 2 + command 1 + length 1 + data 5..10 +
// checksum 1), so at most 10 data bytes. The lower bound of 5 contradicts the frames of section 3
// (3 and 4 data bytes) and is not enforced.
inline constexpr std::size_t kMaxData = 10;
inline constexpr std::size_t kMaxFrame = kOverhead + kMaxData;

// Section 3, the only two commands of the protocol.
enum class Cmd : std::uint8_t {
  check = 0x00,  // 確認コマンド: fixed-code check
  run = 0x10,    // 運転コマンド: run data (target frequency code)
};

// Section 3 No.1: the fixed code 1..4 the master sends and the driver echoes.
inline constexpr std::array<std::uint8_t, 4> kFixedCode = {0x01, 0x12, 0x00, 0x06};
// Section 3 No.1: R4..R7 = 00 00 00 00 when the power-on EEPROM check failed or the code did not
// match (固定コードエラー).
inline constexpr std::array<std::uint8_t, 4> kFixedCodeError = {0x00, 0x00, 0x00, 0x00};

// Section 3 No.2, D5 周波数変更時間 (frequency change time).
inline constexpr std::uint8_t kChangeNormal = 0x01;      // normal: 360 rpm/s ramp
inline constexpr std::uint8_t kChangeContinuous = 0xFF;  // 連続運転モード: continuous mode
// Section 3 No.2 box: 0x00 = error reset & stop; up to 0x0E (under 500 rpm) = stop;
// lowest running speed 504 rpm = 0x1C.
inline constexpr std::uint8_t kCodeResetStop = 0x00;
inline constexpr std::uint8_t kCodeStopMax = 0x0E;
inline constexpr std::uint8_t kCodeLowestRun = 0x1C;

struct Frame {
  std::uint8_t src = 0;
  std::uint8_t dst = 0;
  std::uint8_t cmd = 0;
  std::vector<std::uint8_t> data;  // n + 1 bytes
  friend bool operator==(const Frame&, const Frame&) = default;
};

// The byte that makes the sum of `bytes` plus itself 0x55.
std::uint8_t checksum(ByteView bytes);
// Whole frame on the wire, checksum appended. `data` must hold 1..kMaxData bytes.
Bytes encode(const Frame& f);

// Incremental decoder: looks at the start of `rx`.
//  - incomplete: a frame may still be under way;
//  - frame: a checked frame of `consumed` bytes;
//  - bad: bad_header (unknown command byte, 1 byte dropped), bad_length (length byte over
//    kMaxData - 1, 1 byte dropped), bad_checksum (the whole frame-shaped run dropped), or, when a
//    checked frame starts inside a frame-shaped run whose checksum fails, bad_header with the bytes
//    before that frame (resynchronisation after a truncated frame).
Decoded<Frame> decode(ByteView rx);

// Master -> driver frames of section 3.
Bytes encode_check(std::uint8_t master, std::uint8_t device);
Bytes encode_run(std::uint8_t master, std::uint8_t device, std::uint8_t code, std::uint8_t change);

// Driver -> master replies of section 3.
Bytes encode_check_reply(std::uint8_t device, std::uint8_t master,
                         const std::array<std::uint8_t, 4>& code);

// Section 3 No.2, R4..R11.
struct RunReply {
  std::uint8_t target_code = 0;        // R4 目標周波数 (echo of D4)
  std::uint8_t actual_code = 0;        // R5 実運転周波数
  std::uint8_t reserved = 0;           // R6 予約
  std::uint8_t error_code = 0;         // R7 エラーコード
  std::uint8_t ipm_temp_c = 0;         // R8 IPMセンサー温度 [deg C], e.g. 0x1A = 26
  std::array<std::uint8_t, 3> info{};  // R9..R11 情報 1..3
  friend bool operator==(const RunReply&, const RunReply&) = default;
};
Bytes encode_run_reply(std::uint8_t device, std::uint8_t master, const RunReply& r);

// Field layouts by command and direction; nullopt when the length does not fit.
std::optional<std::array<std::uint8_t, 4>> parse_check(const Frame& f);  // both directions
std::optional<RunReply> parse_run_reply(const Frame& f);
struct RunRequest {
  std::uint8_t code = 0;    // D4
  std::uint8_t change = 0;  // D5
};
std::optional<RunRequest> parse_run_request(const Frame& f);

}  // namespace drivegate::mdriver
