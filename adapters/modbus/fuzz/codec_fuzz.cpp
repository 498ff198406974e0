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
  // A profile's own write codes (point.write_code), laid out as 06 and 16.
  static constexpr modbus_device::CodeLayout kLayouts[] = {{0x41, 0x06}, {0x42, 0x10}};
  const auto rx = in.rest();
  for (const Framing f : {Framing::rtu, Framing::ascii}) {
    for (const modbus_device::CodeLayouts layouts :
         {modbus_device::CodeLayouts{}, modbus_device::CodeLayouts{kLayouts}}) {
      decode_all(rx, [f, layouts](std::span<const std::uint8_t> b) {
        return modbus_device::decode_request(f, b, layouts);
      });
      decode_all(rx, [f, layouts](std::span<const std::uint8_t> b) {
        return modbus_device::decode_reply(f, b, layouts);
      });
    }
  }
  const std::string text(rx.begin(), rx.end());
  (void)modbus_device::parse_profile(text, "fuzz.toml");
}

}  // namespace drivegate::fuzz
