// Fuzz target: a Modbus TCP byte stream through the MBAP parser and the Dispatcher against the
// server tests' fake register image (four 4096-entry tables with an unmapped hole, units 1 and 2;
// unit 5 a pass-through one).
//
// Input: one option byte, then the stream.
//   bit 0     writes complete inside Backend::write (0) or after the segment they arrived in (1)
//   bits 1-2  what the device reports for a write: none, 0x04, 0x0B, 0x06
//   bits 3-7  segment size: 0 = the whole stream in one segment, n = n bytes at a time
#include <array>
#include <cstddef>
#include <cstdint>

#include "fake_backend.h"
#include "fuzz_input.h"
#include "modbus_stream.h"

using drivegate::modbus::Exception;
using drivegate::modbus::test::FakeBackend;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  drivegate::fuzz::FuzzInput in(data, size);
  const std::uint8_t options = in.u8();
  constexpr std::array<Exception, 4> kResults = {Exception::none, Exception::server_device_failure,
                                                 Exception::gateway_target_failed,
                                                 Exception::server_device_busy};

  FakeBackend backend;
  backend.mode = (options & 1) != 0 ? FakeBackend::Mode::deferred : FakeBackend::Mode::immediate;
  backend.device_result = kResults[(options >> 1) & 3];
  backend.reject_value = 0xDEAD;
  auto settle = [&backend] {
    // A pass-through unit's device answers with the request itself (a write's echo), or fails.
    if (!backend.forwards_pending.empty()) {
      const auto& asked =
          backend.forwarded[backend.forwarded.size() - backend.forwards_pending.size()];
      backend.complete_forward(asked, backend.device_result);
      return true;
    }
    if (backend.pending.empty()) return false;
    backend.complete(backend.device_result);
    return true;
  };
  drivegate::fuzz::ModbusStream stream(backend, settle);

  const std::size_t segment = options >> 3;
  while (!in.empty()) {
    const auto bytes = segment == 0 ? in.rest() : in.bytes(segment);
    if (!stream.receive(bytes)) break;
    while (settle()) {
    }
    stream.complete_writes();
  }
  while (settle()) {
  }
  stream.complete_writes();
  return 0;
}
