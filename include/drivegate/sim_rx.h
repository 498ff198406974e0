// What a simulated device does with the bytes it has heard and not yet read as frames: it takes
// the next answer its codec gives for the front of them and drops the bytes that answer covers.
// Header-only, for the adapters' simulators (a driver keeps no buffer: the bus engine does).
#pragma once

#include <algorithm>
#include <cstddef>
#include <optional>
#include <type_traits>

#include "drivegate/bytes.h"
#include "drivegate/codec.h"

namespace drivegate {

// The next answer of `decode` for the front of `buffer` that is a frame or bad bytes, with the
// bytes it covers dropped from `buffer` (at least one, so that a loop over it always moves on);
// nothing while `buffer` is empty or what it holds is incomplete.
//
//   while (const auto d = take_decoded(rx_, [](ByteView b) { return decode_request(b); })) {
//     if (d->status == DecodeStatus::bad) continue;  // a drive ignores a frame it cannot check
//     ...
//   }
template <class Decode>
auto take_decoded(Bytes& buffer, Decode decode)
    -> std::optional<std::invoke_result_t<Decode, ByteView>> {
  if (buffer.empty()) return std::nullopt;
  auto d = decode(ByteView(buffer));
  if (d.status == DecodeStatus::incomplete) return std::nullopt;
  const std::size_t n = std::clamp<std::size_t>(d.consumed, 1, buffer.size());
  buffer.erase(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(n));
  return d;
}

}  // namespace drivegate
