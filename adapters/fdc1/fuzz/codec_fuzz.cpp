// fdc1 codec: the master's decoder of device frames and the simulator's of master frames.
#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  const auto rx = in.rest();
  decode_all(rx, [](std::span<const std::uint8_t> b) { return fdc1::decode_device(b); });
  decode_all(rx, [](std::span<const std::uint8_t> b) { return fdc1::decode_master(b); });
}

}  // namespace drivegate::fuzz
