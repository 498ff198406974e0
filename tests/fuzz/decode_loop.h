// Runs an incremental decoder over a receive buffer the way a bus or a simulator does: decode at
// the front, drop what the verdict consumed, stop at `incomplete`. Checks the decoder contract of
// include/drivegate/codec.h on every step.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "check.h"
#include "drivegate/codec.h"

namespace drivegate::fuzz {

template <class Decode>
void decode_all(std::span<const std::uint8_t> rx, Decode&& decode) {
  while (!rx.empty()) {
    const auto d = decode(rx);
    if (d.status == DecodeStatus::incomplete) return;
    // A frame or a bad verdict always covers at least one byte and never more than there are.
    FUZZ_CHECK(d.consumed >= 1 && d.consumed <= rx.size());
    if (d.status == DecodeStatus::bad) FUZZ_CHECK(static_cast<bool>(d.error));
    rx = rx.subspan(d.consumed);
  }
}

// Each of `decoders` (the master's and the simulator's, say) over the whole of `rx`, in turn.
template <class... Decode>
void decode_each(std::span<const std::uint8_t> rx, Decode&&... decoders) {
  (decode_all(rx, decoders), ...);
}

}  // namespace drivegate::fuzz
