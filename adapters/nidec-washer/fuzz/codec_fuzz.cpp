// nidec-washer codec: the master's reply decoder and the inverter's (simulator's) request decoder.
#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  decode_each(in.rest(), nidec::decode_reply, nidec::decode_request);
}

}  // namespace drivegate::fuzz
