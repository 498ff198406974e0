// The codec of a described protocol: frames <-> bytes for any description (description.h). Bytes
// in, frames out; no I/O, no clock, no logging. A received frame is the first message of its
// direction, in the order the description declares them, whose layout the bytes fit (constants,
// limits and length field) and whose checks hold; bytes that fit no layout are noise, and a
// frame-shaped run whose check fails is dropped up to the next byte that could start a frame, so
// that a good frame which began inside a damaged one is still found (docs/protocols.md, "Frames").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "description.h"
#include "drivegate/bytes.h"
#include "drivegate/codec.h"

namespace drivegate::framed {

// One decoded frame: which message, and its bytes (unstuffed where the framing stuffs), read
// in place: valid while the buffer decoded from is unchanged, and for a stuffed frame until the
// next decode on this thread.
struct Frame {
  std::size_t message = 0;
  ByteView bytes;
};

class Codec {
 public:
  explicit Codec(const Description& d);

  // The message's bytes on the wire: fields from `values` (Message::fields order; missing ones
  // 0), the length field and the checks worked out, stuffed and flagged where the framing is.
  [[nodiscard]] Bytes encode(std::size_t message, std::span<const double> values) const;
  // The frame at the start of `rx` among the messages of one direction.
  [[nodiscard]] Decoded<Frame> decode(Direction dir, ByteView rx) const;
  // A decoded frame's field (Message::fields index), and all of them in order into `out`.
  [[nodiscard]] double value(const Frame& f, std::size_t field) const;
  void values(const Frame& f, std::span<double> out) const;
  // A check's value over `frame`, its range ending at `to_default` unless the check says where.
  [[nodiscard]] std::uint32_t check_value(std::size_t check, ByteView frame,
                                          std::size_t to_default) const;
  // The bytes between a start and an end flag, unstuffed; false and `error` on a bad escape.
  [[nodiscard]] bool unstuff(ByteView wire, Bytes& body, FrameError& error) const;

  [[nodiscard]] const Description& description() const { return d_; }

 private:
  enum class Fit : std::uint8_t { reject, incomplete, good, bad_check, bad_length };
  // A check of a message: where it is, and the range it covers once the message's size is known.
  struct CheckPlan {
    const Token* token = nullptr;
    const Check* check = nullptr;
    std::size_t from = 0;
    std::size_t to = 0;
  };
  // What decoding and encoding a message takes, worked out once.
  struct Plan {
    std::size_t size = 0;
    Bytes skeleton;  // the constants in place, zeros elsewhere
    std::vector<std::pair<std::size_t, std::uint8_t>> constants;  // offset, byte; in order
    std::vector<const Token*> fields;                             // by field index
    std::vector<const Token*> judged;  // fields with limits, or the length field
    std::vector<CheckPlan> checks;
    std::size_t first_check = 0;
    std::size_t length_field = SIZE_MAX;  // the length field's index, if any
  };
  [[nodiscard]] std::uint32_t compute(std::size_t check, const std::uint8_t* data, std::size_t from,
                                      std::size_t to) const;
  // The messages that may start with a byte: a list, or by their second byte too when every one
  // of them has a constant there.
  struct Candidates {
    std::vector<std::size_t> all;
    std::vector<std::vector<std::size_t>> by_second;  // empty, or 256 lists
  };
  Fit fit(std::size_t message, ByteView rx) const;
  [[nodiscard]] bool could_start(Direction dir, ByteView rx) const;
  [[nodiscard]] Decoded<Frame> decode_plain(Direction dir, ByteView rx) const;
  [[nodiscard]] Decoded<Frame> decode_flagged(Direction dir, ByteView rx) const;
  [[nodiscard]] const std::vector<std::size_t>& candidates(Direction dir, ByteView rx) const;

  const Description& d_;
  std::vector<Plan> plans_;
  std::array<std::array<Candidates, 256>, 2> by_first_;
  std::vector<std::array<std::uint32_t, 256>> crc_tables_;  // per check (crc only)
};

// The field value a token holds in `frame` at its offset (the inverse of encoding it).
double read_field(const Token& t, ByteView frame);

}  // namespace drivegate::framed
