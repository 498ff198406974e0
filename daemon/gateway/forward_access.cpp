#include "gateway/forward_access.h"

namespace drivegate {

AccessLevel forward_level(std::span<const std::uint8_t> pdu) {
  if (pdu.empty()) return AccessLevel::maintain;
  // Function codes of the MODBUS Application Protocol Specification V1.1b3.
  switch (pdu[0]) {
    case 0x01:  // 6.1 read coils
    case 0x02:  // 6.2 read discrete inputs
    case 0x03:  // 6.3 read holding registers
    case 0x04:  // 6.4 read input registers
    case 0x07:  // 6.7 read exception status
    case 0x0B:  // 6.9 get comm event counter
    case 0x0C:  // 6.10 get comm event log
    case 0x11:  // 6.13 report server id
    case 0x14:  // 6.14 read file record
    case 0x18:  // 6.18 read FIFO queue
      return AccessLevel::read;
    case 0x08:  // 6.8 diagnostics: only sub-function 0x0000, return query data, changes nothing
      return pdu.size() >= 3 && pdu[1] == 0x00 && pdu[2] == 0x00 ? AccessLevel::read
                                                                 : AccessLevel::maintain;
    case 0x2B:  // 6.19 / 6.21: MEI type 0x0E, read device identification, only reads
      return pdu.size() >= 2 && pdu[1] == 0x0E ? AccessLevel::read : AccessLevel::maintain;
    default:
      return AccessLevel::maintain;
  }
}

}  // namespace drivegate
