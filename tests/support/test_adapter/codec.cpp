// The test-drive frames, both ways.
#include "codec.h"

#include <algorithm>
#include <initializer_list>
#include <numeric>
#include <optional>

namespace drivegate::testdrive {

std::uint8_t sum_byte(ByteView frame) {
  const unsigned sum = std::accumulate(frame.begin(), frame.end(), 0u);
  return static_cast<std::uint8_t>(0x100u - (sum & 0xFFu));
}

bool known_op(std::uint8_t op) {
  return op >= static_cast<std::uint8_t>(Op::read) && op <= static_cast<std::uint8_t>(Op::accel);
}

namespace {

Bytes sealed(Bytes b) {
  b.push_back(sum_byte(b));
  return b;
}

// The frame of `size` bytes starting with one of `starts` at the front of `rx`, checked: nullopt
// where it is one, else what the decoder answers.
template <class Frame>
std::optional<Decoded<Frame>> unframe(ByteView rx, std::initializer_list<std::uint8_t> starts,
                                      std::size_t size) {
  if (rx.empty()) return Decoded<Frame>{};
  if (std::find(starts.begin(), starts.end(), rx[0]) == starts.end()) {
    return decoded_bad<Frame>(1, FrameError::bad_header);
  }
  if (rx.size() < size) return Decoded<Frame>{};
  if (sum_byte(rx.first(size - 1)) != rx[size - 1]) {
    return decoded_bad<Frame>(size, FrameError::bad_checksum);
  }
  if (!known_op(rx[2])) return decoded_bad<Frame>(size, FrameError::bad_field);
  return std::nullopt;
}

}  // namespace

Bytes encode(const Request& r) {
  return sealed({kRequestStart, r.address, static_cast<std::uint8_t>(r.op),
                 static_cast<std::uint8_t>(r.arg >> 8), static_cast<std::uint8_t>(r.arg)});
}

Bytes encode(const Reply& r) {
  const auto speed = static_cast<std::uint16_t>(r.speed_rpm);
  return sealed({r.refused ? kRefusalStart : kReplyStart, r.address,
                 static_cast<std::uint8_t>(r.op), r.state, r.fault,
                 static_cast<std::uint8_t>(speed >> 8), static_cast<std::uint8_t>(speed)});
}

Reply refusal(std::uint8_t address, Op op) {
  Reply r;
  r.address = address;
  r.op = op;
  r.refused = true;
  return r;
}

Decoded<Request> decode_request(ByteView rx) {
  if (auto d = unframe<Request>(rx, {kRequestStart}, kRequestSize)) return *d;
  return decoded_frame(kRequestSize, Request{rx[1], static_cast<Op>(rx[2]),
                                             static_cast<std::uint16_t>((rx[3] << 8) | rx[4])});
}

Decoded<Reply> decode_reply(ByteView rx) {
  if (auto d = unframe<Reply>(rx, {kReplyStart, kRefusalStart}, kReplySize)) return *d;
  return decoded_frame(
      kReplySize, Reply{rx[1], static_cast<Op>(rx[2]), rx[3], rx[4],
                        static_cast<std::int16_t>(static_cast<std::uint16_t>((rx[5] << 8) | rx[6])),
                        rx[0] == kRefusalStart});
}

}  // namespace drivegate::testdrive
