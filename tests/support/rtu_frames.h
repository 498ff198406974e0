// Modbus RTU frames as a test writes them by hand (MODBUS over Serial Line V1.02, 2.5.1: address,
// PDU, CRC low byte first): a frame from its body, and frames and PDUs joined into one run of
// bytes, to build what a hostile client would send.
#pragma once

#include <initializer_list>

#include "drivegate/bytes.h"
#include "drivegate/crc.h"

namespace drivegate::test {

// `body` (address and PDU) and its CRC, as a slave checks it.
inline Bytes with_crc(Bytes body) {
  append_crc16_modbus(body);
  return body;
}

inline Bytes joined(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const Bytes& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

}  // namespace drivegate::test
