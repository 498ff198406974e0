// Helpers for codec tests: feed a frame to an incremental decoder whole, and split at every
// byte, so that a decoder which only works on whole reads cannot pass.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "drivegate/codec.h"

namespace drivegate::test {

using Buffer = std::vector<std::uint8_t>;

// Calls `decode` on a growing prefix of `wire` (as a receive buffer would grow), split after
// `split` bytes: the first call sees wire[0, split), the second the whole. Returns the verdict
// of the first call that was not `incomplete`, or the last incomplete one.
template <class Frame, class Decode>
Decoded<Frame> feed_split(const Buffer& wire, std::size_t split, Decode decode) {
  std::vector<std::uint8_t> rx(wire.begin(), wire.begin() + static_cast<long>(split));
  Decoded<Frame> first = decode(std::span<const std::uint8_t>(rx));
  if (first.status != DecodeStatus::incomplete) return first;
  rx.assign(wire.begin(), wire.end());
  return decode(std::span<const std::uint8_t>(rx));
}

}  // namespace drivegate::test
