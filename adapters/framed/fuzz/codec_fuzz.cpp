// framed: the description parser over any text, and the codec driven by each shipped description
// over any bytes, both directions; every message of the description encoded from fuzzed values
// decodes back to a frame of its size. The driver and the simulator are adapter_fuzz.cpp's,
// made with the demo's description (a specialising adapter's devices need one).
#include <string>

#include "adapter_fuzz.h"
#include "check.h"
#include "codec.h"
#include "decode_loop.h"
#include "description_parser.h"
#include "settings.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  const auto names = framed::shipped_names();
  const std::size_t pick = in.u8() % (names.size() + 1);
  if (pick == names.size()) {
    // Any text as a description: a description or its errors, never a crash or a hang.
    const auto text = in.rest();
    auto r = framed::parse_description(std::string(text.begin(), text.end()), "fuzz.toml");
    if (const auto* d = std::get_if<std::shared_ptr<const framed::Description>>(&r)) {
      const framed::Codec codec(**d);
      for (std::size_t m = 0; m < (*d)->messages.size(); ++m) (void)codec.encode(m, {});
    }
    return;
  }
  std::string error;
  const auto d = framed::load_description(std::string(names[pick]), error);
  FUZZ_CHECK(d != nullptr);
  const framed::Codec codec(*d);
  const auto rx = in.rest();
  for (const auto dir : {framed::Direction::request, framed::Direction::reply}) {
    decode_all(rx, [&](std::span<const std::uint8_t> b) {
      const auto r = codec.decode(dir, b);
      if (r.status == DecodeStatus::frame) {
        FUZZ_CHECK(r.frame.bytes.size() <= d->framing.max_frame);
        std::array<double, framed::kMaxFields> v{};
        codec.values(r.frame, v);
      }
      return r;
    });
  }
  // A message from values the same bytes make: it decodes to a frame of its size (an earlier
  // message of the same direction may take it: the first that fits does).
  const std::size_t m = rx.size() % d->messages.size();
  std::array<double, framed::kMaxFields> values{};
  for (std::size_t i = 0; i < d->messages[m].fields.size() && !rx.empty(); ++i) {
    values[i] = static_cast<double>(rx[i % rx.size()]) * (i % 3 == 0 ? 257.0 : 1.0);
  }
  const Bytes wire = codec.encode(m, {values.data(), d->messages[m].fields.size()});
  const auto back = codec.decode(d->messages[m].direction, wire);
  FUZZ_CHECK(back.status == DecodeStatus::frame);
  FUZZ_CHECK(back.consumed == wire.size());
}

}  // namespace drivegate::fuzz
