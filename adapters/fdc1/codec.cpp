#include "codec.h"

#include "drivegate/bytes.h"

namespace drivegate::fdc1 {
namespace {

// Bytes to drop so that the buffer starts at the next byte that could be a header.
std::size_t resync(ByteView rx, std::uint8_t head) {
  for (std::size_t i = 1; i < rx.size(); ++i) {
    if (rx[i] == head) return i;
  }
  return rx.size();
}

bool pair_holds(ByteView frame) {
  const auto n = frame.size();
  const auto sum = xor_pair(frame.first(n - 2));
  return sum[0] == frame[n - 2] && sum[1] == frame[n - 1];
}

// Bytes 3..20 of a programming frame or its echo.
Program program_fields(ByteView f) {
  Program p;
  p.min_rpm = be16(f[2], f[3]);
  p.max_rpm = be16(f[4], f[5]);
  p.reserved = f[6];
  p.mode = f[7];
  for (std::size_t i = 0; i < p.levels.size(); ++i) {
    p.levels[i] = be16(f[8 + 2 * i], f[9 + 2 * i]);
  }
  return p;
}

Bytes program_frame(const Program& p) {
  Bytes out{kMasterHead0, kProgramHead1};
  put_be16(out, p.min_rpm);
  put_be16(out, p.max_rpm);
  out.push_back(p.reserved);
  out.push_back(p.mode);
  for (const auto level : p.levels) put_be16(out, level);
  const auto sum = xor_pair(out);
  out.push_back(sum[0]);
  out.push_back(sum[1]);
  return out;
}

}  // namespace

std::array<std::uint8_t, 2> xor_pair(ByteView data) {
  std::array<std::uint8_t, 2> sum{0, 0};
  for (std::size_t i = 0; i < data.size(); ++i) sum[i % 2] ^= data[i];
  return sum;
}

std::uint8_t xor_all(ByteView data) {
  std::uint8_t sum = 0;
  for (const auto b : data) sum ^= b;
  return sum;
}

Bytes encode_status(const Status& s) {
  Bytes out{kStatusHead0, kStatusHead1};
  if (s.motor_on) {
    put_be16(out, s.rpm);  // OUTPUT ON: SP1 SP2
  } else {
    out.push_back(0);  // OUTPUT OFF: byte 3 = 0
    out.push_back(s.alarm);
  }
  put_be16(out, s.word);
  const auto sum = xor_pair(out);
  out.push_back(sum[0]);
  out.push_back(sum[1]);
  return out;
}

Bytes encode_speed(const Speed& s) {
  Bytes out{kMasterHead0, kSpeedHead1};
  put_be16(out, s.min_rpm);
  put_be16(out, s.max_rpm);
  out.push_back(kSpeedFixed);
  out.push_back(xor_all(out));
  return out;
}

Bytes encode_program(const Program& p) {
  return program_frame(p);
}

Bytes encode_echo(const Program& p) {
  Bytes out = program_frame(p);
  out[0] = kEchoHead0;
  return out;
}

Decoded<DeviceFrame> decode_device(ByteView rx) {
  if (rx.empty()) return {};
  if (rx[0] != kStatusHead0)
    return decoded_bad<DeviceFrame>(resync(rx, kStatusHead0), FrameError::bad_header);
  if (rx.size() < 2) return {};
  if (rx[1] == kStatusHead1) {
    if (rx.size() < kStatusSize) return {};
    const auto f = rx.first(kStatusSize);
    if (!pair_holds(f))
      return decoded_bad<DeviceFrame>(resync(rx, kStatusHead0), FrameError::bad_checksum);
    Status s;
    s.motor_on = f[2] != 0;
    if (s.motor_on) {
      s.rpm = be16(f[2], f[3]);
    } else {
      s.alarm = f[3];
    }
    s.word = be16(f[4], f[5]);
    return decoded_frame<DeviceFrame>(kStatusSize, s);
  }
  if (rx[1] == kProgramHead1) {
    if (rx.size() < kProgramSize) return {};
    Bytes f(rx.begin(), rx.begin() + kProgramSize);
    bool holds = pair_holds(f);  // checksum recomputed over 27 80
    if (!holds) {
      f[0] = kMasterHead0;  // checksum left as sent over 72 80
      holds = pair_holds(f);
    }
    if (!holds) return decoded_bad<DeviceFrame>(resync(rx, kStatusHead0), FrameError::bad_checksum);
    return decoded_frame<DeviceFrame>(kProgramSize, Echo{program_fields(f)});
  }
  return decoded_bad<DeviceFrame>(resync(rx, kStatusHead0), FrameError::bad_header);
}

Decoded<MasterFrame> decode_master(ByteView rx) {
  if (rx.empty()) return {};
  if (rx[0] != kMasterHead0)
    return decoded_bad<MasterFrame>(resync(rx, kMasterHead0), FrameError::bad_header);
  if (rx.size() < 2) return {};
  if (rx[1] == kSpeedHead1) {
    if (rx.size() < kSpeedSize) return {};
    const auto f = rx.first(kSpeedSize);
    if (xor_all(f.first(kSpeedSize - 1)) != f[kSpeedSize - 1]) {
      return decoded_bad<MasterFrame>(resync(rx, kMasterHead0), FrameError::bad_checksum);
    }
    if (f[6] != kSpeedFixed)
      return decoded_bad<MasterFrame>(resync(rx, kMasterHead0), FrameError::bad_field);
    return decoded_frame<MasterFrame>(kSpeedSize, Speed{be16(f[2], f[3]), be16(f[4], f[5])});
  }
  if (rx[1] == kProgramHead1) {
    if (rx.size() < kProgramSize) return {};
    const auto f = rx.first(kProgramSize);
    if (!pair_holds(f))
      return decoded_bad<MasterFrame>(resync(rx, kMasterHead0), FrameError::bad_checksum);
    return decoded_frame<MasterFrame>(kProgramSize, program_fields(f));
  }
  return decoded_bad<MasterFrame>(resync(rx, kMasterHead0), FrameError::bad_header);
}

}  // namespace drivegate::fdc1
