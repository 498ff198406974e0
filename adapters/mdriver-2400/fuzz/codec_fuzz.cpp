// mdriver-2400 codec: one decoder serves both directions.
#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  decode_all(in.rest(), [](std::span<const std::uint8_t> b) { return mdriver::decode(b); });
}

}  // namespace drivegate::fuzz
