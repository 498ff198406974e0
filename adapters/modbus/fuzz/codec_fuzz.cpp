// modbus codec and profiles: the slave's request decoder and the master's reply decoder, in RTU
// and in ASCII, over the input; then the input as a profile's text (parse_profile validates
// whatever TOML it is handed, and must answer with a profile or errors, never crash or hang).
#include <string>

#include "adapter_fuzz.h"
#include "codec.h"
#include "decode_loop.h"
#include "profile.h"

namespace drivegate::fuzz {

void fuzz_codec(FuzzInput& in) {
  using modbus_device::Framing;
  const auto rx = in.rest();
  for (const Framing f : {Framing::rtu, Framing::ascii}) {
    decode_all(rx, [f](std::span<const std::uint8_t> b) {
      return modbus_device::decode_request(f, b);
    });
    decode_all(rx, [f](std::span<const std::uint8_t> b) {
      return modbus_device::decode_reply(f, b);
    });
  }
  const std::string text(rx.begin(), rx.end());
  (void)modbus_device::parse_profile(text, "fuzz.toml");
}

}  // namespace drivegate::fuzz
