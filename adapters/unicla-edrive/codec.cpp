#include "codec.h"

#include <utility>

#include "drivegate/flagged.h"

namespace drivegate::unicla {

namespace {

// "Cyclic Redundancy Check - CRC": the table in the document is that of polynomial 0x1021.
constexpr std::uint16_t kCrcPoly = 0x1021;
// "Payload Size" is the last header byte.
constexpr std::size_t kPayloadSizeIndex = 7;

}  // namespace

std::uint16_t crc16(ByteView data) {
  std::uint16_t crc = 0;  // calc_crc16 starts from 0
  for (const std::uint8_t byte : data) {
    crc = static_cast<std::uint16_t>(crc ^ (byte << 8));
    for (int bit = 0; bit < 8; ++bit) {
      const bool top = (crc & 0x8000) != 0;
      crc = static_cast<std::uint16_t>(crc << 1);
      if (top) crc = static_cast<std::uint16_t>(crc ^ kCrcPoly);
    }
  }
  return crc;
}

Bytes frame_body(const Frame& f) {
  Bytes body;
  body.reserve(kHeaderSize + f.payload.size() + kCrcSize);
  body.push_back(f.source);
  body.push_back(f.destination);
  body.push_back(f.command);
  body.push_back(f.message_id);
  body.push_back(f.sequence);
  body.push_back(f.reserved1);
  body.push_back(f.reserved2);
  body.push_back(static_cast<std::uint8_t>(f.payload.size()));
  body.insert(body.end(), f.payload.begin(), f.payload.end());
  // "CRC calculation is done before byte stuffing"; the example sends 0xA7 then 0x70.
  put_be16(body, crc16(body));
  return body;
}

Bytes wrap(ByteView body) {
  Bytes wire;
  wire.reserve(body.size() + 8);
  wire.push_back(kFlag);
  for (const std::uint8_t b : body) {
    if (b == kFlag || b == kEscape) {  // "Case 1" and "Case 2"
      wire.push_back(kEscape);
      wire.push_back(static_cast<std::uint8_t>(b ^ kEscapeXor));
    } else {
      wire.push_back(b);
    }
  }
  wire.push_back(kFlag);
  return wire;
}

Bytes encode(const Frame& f) {
  return wrap(frame_body(f));
}

Decoded<Frame> decode(ByteView rx) {
  // "Start and End of Frame": SOF and EOF are both 7E. Past the longest possible frame without an
  // EOF the SOF was not one; "7E 7E" is an EOF followed by a SOF, which opens the next frame.
  const Decoded<std::size_t> at = find_flagged(rx, kFlag, kFlag, kMaxWireSize);
  if (at.status != DecodeStatus::frame) return not_a_frame<Frame>(at);
  const std::size_t end = at.frame;

  Bytes body;
  body.reserve(end);
  for (std::size_t i = 1; i < end; ++i) {
    if (rx[i] != kEscape) {
      body.push_back(rx[i]);
      continue;
    }
    // Only 0x7E and 0x7D are ever stuffed, as 7D 5E and 7D 5D.
    if (i + 1 >= end) return decoded_bad<Frame>(end, FrameError::bad_escape);
    const auto plain = static_cast<std::uint8_t>(rx[i + 1] ^ kEscapeXor);
    if (plain != kFlag && plain != kEscape) return decoded_bad<Frame>(end, FrameError::bad_escape);
    body.push_back(plain);
    ++i;
  }
  if (body.size() < kHeaderSize + kCrcSize) return decoded_bad<Frame>(end, FrameError::bad_length);
  if (body[kPayloadSizeIndex] != body.size() - kHeaderSize - kCrcSize) {
    return decoded_bad<Frame>(end, FrameError::bad_length);
  }
  const std::size_t crc_at = body.size() - kCrcSize;
  const std::uint16_t want = be16(body[crc_at], body[crc_at + 1]);
  if (crc16(ByteView(body).first(crc_at)) != want) {
    return decoded_bad<Frame>(end, FrameError::bad_checksum);
  }

  // "Message Structure": source, destination, command, message id, sequence, two reserved bytes,
  // payload size, then the payload.
  Frame f;
  f.source = body[0];
  f.destination = body[1];
  f.command = body[2];
  f.message_id = body[3];
  f.sequence = body[4];
  f.reserved1 = body[5];
  f.reserved2 = body[6];
  f.payload.assign(body.begin() + static_cast<long>(kHeaderSize),
                   body.begin() + static_cast<long>(crc_at));
  return decoded_frame(end + 1, std::move(f));  // SOF through EOF
}

}  // namespace drivegate::unicla
