// Where a frame between flags lies at the front of received bytes (a start flag, the stuffed
// body, an end flag: unicla-edrive's 7E ... 7E, a described framing with `start`), by the rules
// every such codec follows for the bytes before, between and around the flags. Pure and
// header-only; the unstuffing and the checks are each codec's own.
#pragma once

#include <cstddef>
#include <cstdint>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"

namespace drivegate {

// The flagged frame at the front of `rx`: a frame whose value is the index of its end flag (the
// stuffed body is rx[1, end)), or what a decoder answers when there is none yet:
//   - bytes before a start flag are bad_header, all of them up to the next start flag;
//   - a start flag with no end flag within `max_wire` bytes was not one: it alone is bad_length;
//   - two flags in a row are an end and the next start: the first alone is bad_length;
//   - otherwise, and for no bytes, incomplete.
inline Decoded<std::size_t> find_flagged(ByteView rx, std::uint8_t start, std::uint8_t end_flag,
                                         std::size_t max_wire) {
  if (rx.empty()) return {};
  if (rx[0] != start) {
    std::size_t n = 1;
    while (n < rx.size() && rx[n] != start) ++n;
    return decoded_bad<std::size_t>(n, FrameError::bad_header);
  }
  std::size_t end = 1;
  while (end < rx.size() && rx[end] != end_flag) ++end;
  if (end == rx.size()) {
    if (rx.size() > max_wire) return decoded_bad<std::size_t>(1, FrameError::bad_length);
    return {};
  }
  if (end == 1) return decoded_bad<std::size_t>(1, FrameError::bad_length);
  return decoded_frame<std::size_t>(end + 1, end);
}

// A decoder's answer that is not a frame (incomplete or bad), as a decoder of `Frame` gives it.
template <class Frame, class Other>
Decoded<Frame> not_a_frame(const Decoded<Other>& d) {
  Decoded<Frame> out;
  out.status = d.status;
  out.consumed = d.consumed;
  out.error = d.error;
  return out;
}

}  // namespace drivegate
