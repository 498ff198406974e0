#include "codec.h"

#include <algorithm>
#include <span>
#include <utility>
#include <variant>

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

// A frame, or why the bytes it takes are not one.
template <class Frame>
using Body = std::variant<Frame, FrameError>;

// A frame's second byte, which names it, and its size.
struct Shape {
  std::uint8_t head1;
  std::size_t size;
};
// What the controller sends (OUTPUT, the programming echo) and what the master sends (INPUT
// speed, INPUT programming).
constexpr std::array<Shape, 2> kDeviceFrames = {
    {{kStatusHead1, kStatusSize}, {kProgramHead1, kProgramSize}}};
constexpr std::array<Shape, 2> kMasterFrames = {
    {{kSpeedHead1, kSpeedSize}, {kProgramHead1, kProgramSize}}};

// One frame of the family whose frames all start with `head0`, the second byte naming the frame
// (`shapes`): nothing until the second byte and then the whole frame are in; `body(frame)`
// decodes the frame. A second byte the family has no frame for, or a frame `body` refuses: the
// bytes up to the next `head0` are dropped.
template <class Frame, class Decode>
Decoded<Frame> decode_headed(ByteView rx, std::uint8_t head0, std::span<const Shape> shapes,
                             Decode body) {
  const auto bad = [&](FrameError e) { return decoded_bad<Frame>(resync(rx, head0), e); };
  if (rx.empty()) return {};
  if (rx[0] != head0) return bad(FrameError::bad_header);
  if (rx.size() < 2) return {};
  const auto shape =
      std::find_if(shapes.begin(), shapes.end(), [&](const Shape& s) { return s.head1 == rx[1]; });
  if (shape == shapes.end()) return bad(FrameError::bad_header);
  if (rx.size() < shape->size) return {};
  Body<Frame> b = body(rx.first(shape->size));
  if (const auto* e = std::get_if<FrameError>(&b)) return bad(*e);
  return decoded_frame<Frame>(shape->size, std::move(std::get<Frame>(b)));
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
  return decode_headed<DeviceFrame>(
      rx, kStatusHead0, kDeviceFrames, [](ByteView f) -> Body<DeviceFrame> {
        if (f[1] == kProgramHead1) {
          Bytes g(f.begin(), f.end());
          bool holds = pair_holds(g);  // checksum recomputed over 27 80
          if (!holds) {
            g[0] = kMasterHead0;  // checksum left as sent over 72 80
            holds = pair_holds(g);
          }
          if (!holds) return FrameError::bad_checksum;
          return DeviceFrame{Echo{program_fields(g)}};
        }
        if (!pair_holds(f)) return FrameError::bad_checksum;
        Status s;
        s.motor_on = f[2] != 0;
        if (s.motor_on) {
          s.rpm = be16(f[2], f[3]);
        } else {
          s.alarm = f[3];
        }
        s.word = be16(f[4], f[5]);
        return DeviceFrame{s};
      });
}

Decoded<MasterFrame> decode_master(ByteView rx) {
  return decode_headed<MasterFrame>(rx, kMasterHead0, kMasterFrames,
                                    [](ByteView f) -> Body<MasterFrame> {
                                      if (f[1] == kProgramHead1) {
                                        if (!pair_holds(f)) return FrameError::bad_checksum;
                                        return MasterFrame{program_fields(f)};
                                      }
                                      if (xor_all(f.first(kSpeedSize - 1)) != f[kSpeedSize - 1])
                                        return FrameError::bad_checksum;
                                      if (f[6] != kSpeedFixed) return FrameError::bad_field;
                                      return MasterFrame{Speed{be16(f[2], f[3]), be16(f[4], f[5])}};
                                    });
}

}  // namespace drivegate::fdc1
