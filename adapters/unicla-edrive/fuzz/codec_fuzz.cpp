// unicla-edrive codec: one byte-stuffed frame decoder serves both directions.
#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  decode_all(in.rest(), [](std::span<const std::uint8_t> b) { return unicla::decode(b); });
}

}  // namespace drivegate::fuzz
