// CRC-16 of Modbus RTU frames, which several drive protocols borrow (ed3100, and the modbus
// adapter itself). Pure.
#pragma once

#include <cstdint>

#include "drivegate/bytes.h"

namespace drivegate {

// Register preset to 0xFFFF; for each byte XOR it in, then eight times shift right, XOR-ing 0xA001
// (0x8005 reflected) whenever the bit shifted out was 1 ("MODBUS over Serial Line V1.02", 6.2.2).
// One byte into the register (a running CRC: start from 0xFFFF).
constexpr std::uint16_t crc16_modbus_update(std::uint16_t reg, std::uint8_t b) {
  reg ^= b;
  for (int bit = 0; bit < 8; ++bit) {
    reg = (reg & 0x0001) != 0 ? static_cast<std::uint16_t>((reg >> 1) ^ 0xA001)
                              : static_cast<std::uint16_t>(reg >> 1);
  }
  return reg;
}
constexpr std::uint16_t crc16_modbus(ByteView data) {
  std::uint16_t reg = 0xFFFF;
  for (const std::uint8_t b : data) reg = crc16_modbus_update(reg, b);
  return reg;
}

// Appends the CRC of `frame`, low byte first (6.2.2).
inline void append_crc16_modbus(Bytes& frame) {
  const std::uint16_t c = crc16_modbus(frame);
  frame.push_back(lo8(c));
  frame.push_back(hi8(c));
}

// Whether the last two bytes of `frame` are the CRC of the bytes before them.
constexpr bool crc16_modbus_holds(ByteView frame) {
  if (frame.size() < 3) return false;
  const std::size_t n = frame.size() - 2;
  const std::uint16_t want = crc16_modbus(frame.first(n));
  return frame[n] == lo8(want) && frame[n + 1] == hi8(want);
}

}  // namespace drivegate
