#include "codec.h"

#include <algorithm>

namespace drivegate::nidec {
namespace {

// 5.16: the NACK frame's body; its checksum is 5A again.
constexpr std::array<std::uint8_t, 5> kNackBody = {0x00, 0xFF, 0x00, 0xFF, 0x00};
// 5.15: the FCT command carries this fixed pattern in bytes 3..10.
constexpr std::array<std::uint8_t, kRequestData> kFctPattern = {0x12, 0x00, 0x34, 0x00,
                                                                0x56, 0x00, 0x78, 0x00};

bool checksum_holds(ByteView frame) {
  return xor_of(frame.first(frame.size() - 1)) == frame.back();
}

// 4.2 / 5.16: a slave frame starts A5, or 5A for the NACK. 4.1: a master frame starts A5.
bool starts_reply(std::uint8_t b) {
  return b == kHeader || b == kNackHeader;
}
bool starts_request(std::uint8_t b) {
  return b == kHeader;
}

// A frame-shaped run whose XOR does not hold. A byte may have been lost, so a good frame can
// start inside it: drop only up to the next frame start after its first byte, or the whole run
// when it holds none. Still a bad checksum, so the bus counts a damaged frame.
template <class Frame, class Starts>
Decoded<Frame> bad_checksum(ByteView run, Starts starts) {
  const auto next = std::find_if(run.begin() + 1, run.end(), starts);
  return decoded_bad<Frame>(static_cast<std::size_t>(next - run.begin()), FrameError::bad_checksum);
}

}  // namespace

bool is_v07_mode(std::uint8_t mode) {
  switch (static_cast<Mode>(mode)) {
    case Mode::ping:
    case Mode::request:
    case Mode::cw:
    case Mode::ccw:
    case Mode::agitation:
    case Mode::spin:
    case Mode::forced_brake:
    case Mode::free_shaft_spin:
    case Mode::stop:
    case Mode::brake:
    case Mode::voltage_detection:
    case Mode::weight_detection:
    case Mode::fabric_detection:
    case Mode::fct_test:
      return true;
  }
  return false;
}

std::uint8_t xor_of(ByteView bytes) {
  std::uint8_t x = 0;
  for (const std::uint8_t b : bytes) x ^= b;
  return x;
}

Bytes encode(const Request& r) {
  Bytes out;
  out.reserve(kRequestSize);
  out.push_back(kHeader);
  out.push_back(static_cast<std::uint8_t>(r.mode));
  out.insert(out.end(), r.data.begin(), r.data.end());
  out.push_back(xor_of(out));
  return out;
}

Request make_bare(Mode mode) {
  return Request{mode, {}};
}

Request make_ping(std::uint8_t platform, std::uint16_t empty_raw_weight) {
  // 5.1: platform, empty raw weight high, low, then five zero bytes.
  return Request{Mode::ping, {platform, hi8(empty_raw_weight), lo8(empty_raw_weight)}};
}

Request make_run(Mode mode, std::uint16_t rpm, std::uint16_t accel_100ms) {
  // 5.3 / 5.4 / 5.6 / 5.14: speed high, low, accel time high, low (x 100 ms), four zero bytes.
  return Request{mode, {hi8(rpm), lo8(rpm), hi8(accel_100ms), lo8(accel_100ms)}};
}

Request make_agitation(std::uint16_t rpm, const AgitationTiming& t) {
  // 5.5: speed high, low, then accel, decel, CW on, CW off, CCW on, CCW off (x 100 ms each).
  return Request{Mode::agitation,
                 {hi8(rpm), lo8(rpm), t.accel, t.decel, t.cw_on, t.cw_off, t.ccw_on, t.ccw_off}};
}

Request make_forced_brake(bool enable) {
  // 5.13: byte 3 is 1 = enable, 0 = disable.
  return Request{Mode::forced_brake, {static_cast<std::uint8_t>(enable ? 1 : 0)}};
}

Request make_fct() {
  return Request{Mode::fct_test, kFctPattern};
}

Bytes encode(const Reply& r) {
  Bytes out;
  if (r.nack) {
    out.push_back(kNackHeader);
    out.insert(out.end(), kNackBody.begin(), kNackBody.end());
  } else {
    out.push_back(kHeader);
    out.push_back(static_cast<std::uint8_t>(r.mode));
    out.insert(out.end(), r.data.begin(), r.data.begin() + r.size);
  }
  out.push_back(xor_of(out));
  return out;
}

Bytes encode_reply(Mode mode, std::array<std::uint8_t, 4> data) {
  Reply r;
  r.mode = mode;
  r.size = 4;
  std::copy(data.begin(), data.end(), r.data.begin());
  return encode(r);
}

Bytes encode_fct_reply(std::array<std::uint8_t, kMaxReplyData> data) {
  Reply r;
  r.mode = Mode::fct_test;
  r.size = kMaxReplyData;
  r.data = data;
  return encode(r);
}

Bytes encode_nack() {
  Reply r;
  r.nack = true;
  return encode(r);
}

Decoded<Reply> decode_reply(ByteView rx) {
  Decoded<Reply> d;
  if (rx.empty()) return d;
  const std::uint8_t header = rx[0];
  if (header != kHeader && header != kNackHeader)
    return decoded_bad<Reply>(1, FrameError::bad_header);
  std::size_t size = kReplySize;
  if (header == kHeader) {
    if (rx.size() < 2) return d;
    if (!is_v07_mode(rx[1])) return decoded_bad<Reply>(1, FrameError::bad_field);
    if (static_cast<Mode>(rx[1]) == Mode::fct_test) size = kFctReplySize;  // 5.15
  }
  if (rx.size() < size) return d;
  const ByteView frame = rx.first(size);
  if (!checksum_holds(frame)) return bad_checksum<Reply>(frame, starts_reply);
  d.status = DecodeStatus::frame;
  d.consumed = size;
  if (header == kNackHeader) {
    // 5.16: any checksummed 5A frame is taken as the NACK; its body carries no information.
    d.frame.nack = true;
    return d;
  }
  d.frame.mode = static_cast<Mode>(frame[1]);
  d.frame.size = static_cast<std::uint8_t>(size - 3);
  std::copy(frame.begin() + 2, frame.end() - 1, d.frame.data.begin());
  return d;
}

Decoded<Request> decode_request(ByteView rx) {
  Decoded<Request> d;
  if (rx.empty()) return d;
  if (rx[0] != kHeader) return decoded_bad<Request>(1, FrameError::bad_header);
  if (rx.size() < kRequestSize) return d;
  const ByteView frame = rx.first(kRequestSize);
  if (!checksum_holds(frame)) return bad_checksum<Request>(frame, starts_request);
  if (!is_v07_mode(frame[1])) return decoded_bad<Request>(kRequestSize, FrameError::bad_field);
  d.status = DecodeStatus::frame;
  d.consumed = kRequestSize;
  d.frame.mode = static_cast<Mode>(frame[1]);
  std::copy(frame.begin() + 2, frame.end() - 1, d.frame.data.begin());
  return d;
}

}  // namespace drivegate::nidec
