// ed3100 codec: the drive side's request decoder, and the master's reply decoder for a reply
// shape the input chooses (function 03 / 06 / 10, register, data words).
#include <array>

#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  constexpr std::array<std::uint8_t, 4> kFunctions = {ed3100::kFnRead, ed3100::kFnWriteSingle,
                                                      ed3100::kFnWriteMultiple, 0x00};
  ed3100::ReplyShape shape;
  shape.function = kFunctions[in.u8() % kFunctions.size()];
  shape.reg = in.u16();
  shape.words = static_cast<std::uint16_t>(in.u8() % 130);
  const auto rx = in.rest();
  decode_all(rx, [](std::span<const std::uint8_t> b) { return ed3100::decode_request(b); });
  decode_all(rx,
             [&shape](std::span<const std::uint8_t> b) { return ed3100::decode_reply(b, shape); });
}

}  // namespace drivegate::fuzz
