// Fuzz target: what a serial device server on the network sends a tcp:// or rfc2217:// bus, through
// the Telnet decoder (RFC 854 / 855) and the RFC 2217 answer parser, as Rfc2217Transport feeds
// them: reads of any size, a command split anywhere between two of them.
//
// Invariants: the decoder's output does not depend on where the stream was split (segments of any
// size give the data and events one read of the whole stream gives); it never produces more data
// than it was given; a subnegotiation's payload is bounded (kMaxPayload: a longer one is cut
// there, never grown); a negotiation's verb is DO, DONT, WILL or WONT; data escaped by escape()
// decodes back to itself with no event, and a subnegotiation() to exactly that event; take_answer()
// and mismatch() accept every COM-PORT-OPTION payload.
//
// Input: one option byte (bits 0-5: segment size, 0 = the whole stream at once), then the stream.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "check.h"
#include "fuzz_input.h"
#include "transport/telnet_codec.h"

namespace {

using drivegate::Bytes;
using drivegate::ByteView;
namespace telnet = drivegate::telnet;
namespace rfc2217 = drivegate::rfc2217;

struct Decoded {
  Bytes data;
  std::vector<telnet::Event> events;
};

Decoded decode(ByteView stream, std::size_t segment) {
  telnet::Decoder decoder;
  Decoded out;
  if (segment == 0) segment = stream.size() + 1;
  for (std::size_t at = 0; at < stream.size(); at += segment) {
    const std::size_t n = std::min(segment, stream.size() - at);
    decoder.feed(stream.subspan(at, n), out.data, out.events);
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  drivegate::fuzz::FuzzInput in(data, size);
  const std::size_t segment = in.u8() & 0x3F;
  const auto rest = in.rest();
  const ByteView stream(rest.data(), rest.size());

  const Decoded whole = decode(stream, 0);
  const Decoded split = decode(stream, segment);
  FUZZ_CHECK(split.data == whole.data);
  FUZZ_CHECK(split.events == whole.events);
  FUZZ_CHECK(whole.data.size() <= stream.size());

  rfc2217::ServerSettings settings;
  for (const auto& e : whole.events) {
    if (e.kind == telnet::Event::Kind::negotiation) {
      FUZZ_CHECK(e.verb == telnet::kDo || e.verb == telnet::kDont || e.verb == telnet::kWill ||
                 e.verb == telnet::kWont);
      FUZZ_CHECK(e.payload.empty());
    } else {
      FUZZ_CHECK(e.payload.size() <= 64);  // telnet::Decoder::kMaxPayload
      if (e.option == telnet::kComPortOption) rfc2217::take_answer(e.payload, settings);
    }
  }
  (void)rfc2217::mismatch(rfc2217::LineSettings{}, settings);

  // Round trips: the stream as data, escaped, comes back as itself; as a subnegotiation payload
  // (when short enough to be kept), as exactly that event.
  Bytes escaped;
  telnet::escape(stream, escaped);
  const Decoded back = decode(escaped, segment);
  FUZZ_CHECK(back.events.empty());
  FUZZ_CHECK(back.data == Bytes(stream.begin(), stream.end()));
  if (stream.size() <= 64) {
    const Decoded sub = decode(telnet::subnegotiation(telnet::kComPortOption, stream), segment);
    FUZZ_CHECK(sub.data.empty());
    FUZZ_CHECK(sub.events.size() == 1);
    FUZZ_CHECK(sub.events[0].kind == telnet::Event::Kind::subnegotiation);
    FUZZ_CHECK(sub.events[0].option == telnet::kComPortOption);
    FUZZ_CHECK(sub.events[0].payload == Bytes(stream.begin(), stream.end()));
  }
  return 0;
}
