// The receive side of a Modbus serial-line slave: which bytes a master sent are a request, and
// when the reply may start. Pure: bytes and the times they arrived in, frames and deadlines out
// (the host owns the port and the timer). The frame itself is the codec's (serial_codec.h).
//
// RTU on a serial line (MODBUS over Serial Line V1.02, "Serial Line", 2.5.1.1): a frame is
// preceded and followed by a silence of at least 3.5 character times; a silence of more than 1.5
// character times inside it makes it incomplete, and it is discarded (gaps up to
// LineTiming::latency excepted: the port's delivery, not the master's pauses). Above 19200 baud the two
// times are fixed at 750 us and 1.75 ms (2.5.1.1, note). A request is taken as soon as its length
// (known from its function code) and CRC are in, and the reply may start 3.5 characters after its
// last byte: `reply_at`. Bytes that arrive while the line should be silent, or a frame that does
// not check, are thrown away up to the next 3.5-character silence, and counted.
//
// RTU over TCP (`Delimit::length`): the same frames with no line timing; a frame ends where its
// length says, and bytes that cannot start one are discarded (the connection's stream is resynced
// on the next read that starts with a good frame).
//
// ASCII (2.5.2.1): ':' starts a frame (and restarts one: the bytes before it are dropped), CR LF
// ends it, the LRC checks it; more than `ascii_timeout` between two characters discards it
// (Serial Line 2.5.2.1: 1 s by default).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "drivegate/bytes.h"
#include "modbus_serial/serial_codec.h"

namespace drivegate::modbus {

using SerialClock = std::chrono::steady_clock;

enum class Delimit : std::uint8_t {
  silence,  // a serial line: the character times say where frames end
  length,   // a byte stream (RTU over TCP): the frame's length does
};

// The character times of a line (Serial Line 2.5.1.1).
struct LineTiming {
  // One character on the wire. A read of n bytes that completes at t began on the line at
  // t - n characters, and the silence before it is measured to there (0: every byte of a read
  // arrived at its time, as on a pseudo-terminal written in whole frames).
  std::chrono::microseconds char_time{0};
  std::chrono::microseconds t15{750};
  std::chrono::microseconds t35{1750};
  std::chrono::milliseconds ascii_timeout{1000};
  // How late the port may hand over bytes it received: a UART's FIFO hands a frame's tail over
  // only after 4 characters of silence, a USB adapter holds bytes for its latency timer (16 ms by
  // default on FTDI's). Inside an RTU frame the framer takes a pause up to this long for the
  // port's, not the master's: no gap, no end of a frame that is not all in yet. 0: the
  // specification's 1.5 and 3.5 characters alone (a port that delivers each byte as it comes).
  std::chrono::microseconds latency{0};
};
// The times for `baud` and bits per character (start + data + parity + stop): one character,
// 1.5 and 3.5 of them, or the fixed 750 us / 1.75 ms above 19200 baud.
LineTiming line_timing(unsigned baud, unsigned bits_per_char);

// What the framer found. Every byte received ends up in exactly one of them (or is still
// buffered), so the counters the host keeps from them add up.
struct FramerEvent {
  enum class Kind : std::uint8_t {
    request,       // `adu` is a whole request that checked
    bad_checksum,  // a frame of the right shape whose CRC / LRC is wrong (FC 08 0x0C counts it)
    broken,        // a frame cut by a gap longer than 1.5 characters (RTU) or than the ASCII
                   // timeout, or bytes that cannot start one (noise): discarded
    overrun,       // more bytes than the longest frame before a silence (FC 08 0x12 counts it)
  };
  Kind kind = Kind::request;
  modbus_serial::Adu adu;  // request only
  std::size_t bytes = 0;   // how many received bytes it accounts for
  // request: its last byte's arrival; the reply may start at reply_at.
  SerialClock::time_point reply_at{};
};

class SlaveFramer {
 public:
  SlaveFramer(modbus_serial::Framing framing, Delimit delimit, LineTiming timing);

  // `bytes` arrived at `now` (times never go backwards). Events are queued for next().
  void feed(ByteView bytes, SerialClock::time_point now);
  // When expire() must run next (a silence or a timeout that ends what is buffered), if ever.
  [[nodiscard]] std::optional<SerialClock::time_point> deadline() const;
  // Time passed to `now` with nothing received: ends a partial frame or a discard run whose
  // silence has come.
  void expire(SerialClock::time_point now);
  // The oldest event not yet taken.
  std::optional<FramerEvent> next();
  // The host has put its reply to the last request on the line (or decided on none): the
  // silence that request asked for is over, and what comes next may start a frame at once.
  void replied() { after_request_ = false; }
  // Bytes held that may still become a frame (or are being skipped): a partial frame.
  [[nodiscard]] bool partial() const { return !rx_.empty() || skipping_; }
  // Drops everything buffered (the port was closed).
  void reset();

 private:
  void settle(SerialClock::time_point now);
  void take_frames(SerialClock::time_point now);
  void push(FramerEvent::Kind kind, std::size_t bytes);
  void skip_rest(FramerEvent::Kind kind);

  modbus_serial::Framing framing_;
  Delimit delimit_;
  LineTiming timing_;
  Bytes rx_;
  std::optional<SerialClock::time_point> last_;  // the last byte's arrival, while rx_ or skipping_
  // The latest time known to have passed (the last read or expire()): no byte of a later read
  // began on the wire before it.
  std::optional<SerialClock::time_point> floor_;
  std::optional<SerialClock::time_point> read_floor_;  // floor_ as the read being taken began
  bool skipping_ = false;  // RTU: discarding up to the next 3.5-character silence
  bool broken_ = false;    // RTU: the bytes in rx_ had a gap longer than 1.5 characters
  bool after_request_ = false;  // RTU: a request was taken, and neither a silence nor a reply
                                // has followed it yet
  std::size_t skipped_ = 0;
  FramerEvent::Kind skip_kind_ = FramerEvent::Kind::broken;
  std::vector<FramerEvent> events_;
  std::size_t taken_ = 0;
};

}  // namespace drivegate::modbus
