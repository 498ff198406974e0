// fdc1 codec: the master's decoder of device frames and the simulator's of master frames.
#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  decode_each(in.rest(), fdc1::decode_device, fdc1::decode_master);
}

}  // namespace drivegate::fuzz
