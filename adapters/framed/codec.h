// The codec of a described protocol: frames <-> bytes for any description (description.h). Bytes
// in, frames out; no I/O, no clock, no logging. A received frame is the first message of its
// direction, in the order the description declares them, whose layout the bytes fit (constants,
// limits and length field) and whose checks hold; bytes that fit no layout are noise, and a
// frame-shaped run whose check fails is dropped up to the next byte that could start a frame, so
// that a good frame which began inside a damaged one is still found (docs/protocols.md, "Frames").
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "description.h"
#include "drivegate/bytes.h"
#include "drivegate/codec.h"

namespace drivegate::framed {

// One decoded frame: which message, and its fields' values (Message::fields order).
struct Frame {
  std::size_t message = 0;
  std::array<double, kMaxFields> fields{};
  [[nodiscard]] std::span<const double> values(std::size_t count) const {
    return {fields.data(), count};
  }
};

class Codec {
 public:
  explicit Codec(const Description& d);

  // The message's bytes on the wire: fields from `values` (Message::fields order; missing ones
  // 0), the length field and the checks worked out, stuffed and flagged where the framing is.
  [[nodiscard]] Bytes encode(std::size_t message, std::span<const double> values) const;
  // The frame at the start of `rx` among the messages of one direction.
  [[nodiscard]] Decoded<Frame> decode(Direction dir, ByteView rx) const;
  // A check's value over `frame`, its range ending at `to_default` unless the check says where.
  [[nodiscard]] std::uint32_t check_value(std::size_t check, ByteView frame,
                                          std::size_t to_default) const;
  // The bytes between a start and an end flag, unstuffed; false and `error` on a bad escape.
  [[nodiscard]] bool unstuff(ByteView wire, Bytes& body, FrameError& error) const;

  [[nodiscard]] const Description& description() const { return d_; }

 private:
  enum class Fit : std::uint8_t { reject, incomplete, good, bad_check, bad_length };
  Fit fit(const Message& m, ByteView rx, Frame* out) const;
  [[nodiscard]] bool could_start(Direction dir, ByteView rx) const;
  [[nodiscard]] Decoded<Frame> decode_plain(Direction dir, ByteView rx) const;
  [[nodiscard]] Decoded<Frame> decode_flagged(Direction dir, ByteView rx) const;
  [[nodiscard]] std::span<const std::size_t> candidates(Direction dir, std::uint8_t first) const;

  const Description& d_;
  // Per direction and first byte, the messages that may start with it, in declaration order.
  std::array<std::array<std::vector<std::size_t>, 256>, 2> by_first_;
  std::vector<std::array<std::uint32_t, 256>> crc_tables_;  // per check (crc only)
};

// The field value a token holds in `frame` at its offset (the inverse of encoding it).
double read_field(const Token& t, ByteView frame);

}  // namespace drivegate::framed
