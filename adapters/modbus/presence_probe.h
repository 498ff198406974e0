// The request that asks whether a slave is there, shared by `drivegate scan` and pass-through's
// presence check: read one holding register at 0 (Application Protocol 6.3). A slave with no
// register there answers exception 02, which proves it is there just as well.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "codec.h"

namespace drivegate::modbus_device {

inline constexpr std::array<std::uint8_t, 5> kPresenceProbe = {fc::read_holding_registers, 0x00,
                                                               0x00, 0x00, 0x01};
// Its longest good reply: function, byte count 2, one register (6.3, "Response"); an exception
// reply (7) is shorter.
inline constexpr std::size_t kPresenceProbeReplyPdu = 4;

}  // namespace drivegate::modbus_device
