// nidec-washer codec: the master's reply decoder and the inverter's (simulator's) request decoder.
#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  const auto rx = in.rest();
  decode_all(rx, [](std::span<const std::uint8_t> b) { return nidec::decode_reply(b); });
  decode_all(rx, [](std::span<const std::uint8_t> b) { return nidec::decode_request(b); });
}

}  // namespace drivegate::fuzz
