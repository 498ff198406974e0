// What a master (the profile driver, the pass-through driver) makes of bytes decode_reply()
// rejected: driver.h's damaged(), with RTU's one twist. RTU has no start marker, so a CRC failure
// whose first byte is not the slave's address is a window on noise rather than its damaged reply:
// one byte is skipped and the rest looked at again.
#pragma once

#include "codec.h"
#include "drivegate/driver.h"

namespace drivegate::modbus_device {

inline RxVerdict rejected(Framing framing, const Decoded<Adu>& d, ByteView rx,
                          std::uint8_t address) {
  if (framing == Framing::rtu && d.error == FrameError::bad_checksum && rx[0] != address) {
    return {RxKind::noise, 1};
  }
  return damaged(d);
}

}  // namespace drivegate::modbus_device
