// The shape every adapter codec's incremental decoder answers in, and the framing errors it
// names. A codec is pure: bytes in, frames out. No I/O, no clock, no logging.
#pragma once

#include <cstddef>
#include <string>
#include <system_error>
#include <utility>

namespace drivegate {

enum class DecodeStatus : unsigned char {
  incomplete,  // the bytes so far may still become a frame: call again with more
  frame,       // a whole, checked frame of `consumed` bytes
  bad,         // `consumed` bytes can never be part of a good frame: drop them, see `error`
};

enum class FrameError {
  ok = 0,
  bad_checksum = 1,  // frame-shaped, but the checksum does not hold
  bad_header,        // the first byte(s) cannot start a frame
  bad_length,        // a length field outside what the protocol allows
  bad_field,         // a field value the protocol does not define
  bad_escape,        // a stuffing escape followed by a byte it cannot escape
  unexpected_frame,  // a good frame of a kind not expected here
};

class FrameErrorCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "drivegate.frame"; }
  std::string message(int ev) const override {
    switch (static_cast<FrameError>(ev)) {
      case FrameError::ok:
        return "ok";
      case FrameError::bad_checksum:
        return "bad checksum";
      case FrameError::bad_header:
        return "bad header";
      case FrameError::bad_length:
        return "bad length";
      case FrameError::bad_field:
        return "bad field";
      case FrameError::bad_escape:
        return "bad escape sequence";
      case FrameError::unexpected_frame:
        return "unexpected frame";
    }
    return "unknown frame error";
  }
};

inline const std::error_category& frame_category() noexcept {
  static const FrameErrorCategory category;
  return category;
}

inline std::error_code make_error_code(FrameError e) noexcept {
  return {static_cast<int>(e), frame_category()};
}

template <class Frame>
struct Decoded {
  DecodeStatus status = DecodeStatus::incomplete;
  std::size_t consumed = 0;
  Frame frame{};          // valid when status == frame
  std::error_code error;  // set when status == bad
};

// The two non-incomplete answers, for decoders to return.
template <class Frame>
Decoded<Frame> decoded_bad(std::size_t consumed, FrameError e) {
  Decoded<Frame> d;
  d.status = DecodeStatus::bad;
  d.consumed = consumed;
  d.error = make_error_code(e);
  return d;
}
template <class Frame>
Decoded<Frame> decoded_frame(std::size_t consumed, Frame f) {
  Decoded<Frame> d;
  d.status = DecodeStatus::frame;
  d.consumed = consumed;
  d.frame = std::move(f);
  return d;
}

}  // namespace drivegate

template <>
struct std::is_error_code_enum<drivegate::FrameError> : std::true_type {};
