// Codec tests: golden vectors of eDrive RS485 Interface V16 and shared/specs/README.md,
// stuffing both ways, and every kind of bad frame.
#include "codec.h"

#include <gtest/gtest.h>

#include "feed.h"

namespace drivegate::unicla {
namespace {

using test::Buffer;

Decoded<Frame> dec(ByteView rx) {
  return decode(rx);
}

Frame status_read(std::uint8_t dst, std::uint8_t seq) {
  Frame f;
  f.source = kMasterAddress;
  f.destination = dst;
  f.command = 0xC0;
  f.message_id = 0x01;
  f.sequence = seq;
  return f;
}

// "Cyclic Redundancy Check - CRC", CRC example: 00 01 c0 01 36 00 00 00 -> a7 70.
TEST(UniclaCodec, CrcGoldenVectorFromDocument) {
  const Buffer header = {0x00, 0x01, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00};
  EXPECT_EQ(crc16(header), 0xA770);
}

// CRC-16/XMODEM's published check value ("123456789" -> 0x31C3): the table in the document is
// that of poly 0x1021, init 0, so this must hold too.
TEST(UniclaCodec, CrcXmodemCheckValue) {
  const std::string s = "123456789";
  EXPECT_EQ(crc16(ByteView(reinterpret_cast<const std::uint8_t*>(s.data()), s.size())), 0x31C3);
  EXPECT_EQ(crc16({}), 0x0000);  // calc_crc16 starts from 0
}

// "Examples / Status Read from Device Id 0x01" with the CRC example's sequence 0x36.
TEST(UniclaCodec, EncodesStatusReadGolden) {
  const Buffer want = {0x7E, 0x00, 0x01, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0xA7, 0x70, 0x7E};
  EXPECT_EQ(encode(status_read(0x01, 0x36)), want);
}

TEST(UniclaCodec, DecodesStatusReadGoldenWholeAndSplit) {
  const Buffer wire = {0x7E, 0x00, 0x01, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0xA7, 0x70, 0x7E};
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const auto d = test::feed_split<Frame>(wire, split, dec);
    ASSERT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, wire.size());
    EXPECT_EQ(d.frame, status_read(0x01, 0x36));
  }
}

// "Examples / Set Run State on Device Id 0x01": speed 1000 = 03 E8. The document leaves the
// sequence and CRC as XX; with sequence 0x36 the CRC-16/XMODEM of the body is 34 CC.
TEST(UniclaCodec, EncodesSetRunStateExample) {
  Frame f;
  f.source = 0x00;
  f.destination = 0x01;
  f.command = 0xC1;
  f.message_id = 0xC0;
  f.sequence = 0x36;
  f.payload = {0x03, 0xE8};
  const Buffer want = {0x7E, 0x00, 0x01, 0xC1, 0xC0, 0x36, 0x00,
                       0x00, 0x02, 0x03, 0xE8, 0x34, 0xCC, 0x7E};
  EXPECT_EQ(encode(f), want);
  const auto d = decode(want);
  ASSERT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.frame, f);
}

// "Byte Stuffing": 7E -> 7D 5E (Case 1), 7D -> 7D 5D (Case 2), over header, payload and CRC.
TEST(UniclaCodec, StuffsFlagAndEscapeInPayload) {
  Frame f;
  f.source = 0x01;
  f.destination = 0x00;
  f.command = 0xC0;
  f.message_id = 0x01;
  f.sequence = 0x7E;  // in the header too
  f.payload = {0x7E, 0x11, 0x7D, 0x7E, 0x7D};
  const Buffer body = frame_body(f);
  const Buffer wire = encode(f);
  // Body: 01 00 C0 01 7E 00 00 05 7E 11 7D 7E 7D crc crc
  Buffer want = {0x7E, 0x01, 0x00, 0xC0, 0x01, 0x7D, 0x5E, 0x00, 0x00, 0x05,
                 0x7D, 0x5E, 0x11, 0x7D, 0x5D, 0x7D, 0x5E, 0x7D, 0x5D};
  for (std::size_t i = body.size() - 2; i < body.size(); ++i) {
    if (body[i] == 0x7E || body[i] == 0x7D) {
      want.push_back(0x7D);
      want.push_back(static_cast<std::uint8_t>(body[i] ^ 0x20));
    } else {
      want.push_back(body[i]);
    }
  }
  want.push_back(0x7E);
  EXPECT_EQ(wire, want);
  // No flag between the delimiters.
  for (std::size_t i = 1; i + 1 < wire.size(); ++i) EXPECT_NE(wire[i], 0x7E) << i;
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const auto d = test::feed_split<Frame>(wire, split, dec);
    ASSERT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.frame, f);
  }
}

// A CRC that itself needs stuffing: search a sequence number whose CRC holds a 7E or 7D byte.
TEST(UniclaCodec, StuffsCrcBytes) {
  bool found = false;
  for (int seq = 0; seq < 256 && !found; ++seq) {
    Frame f = status_read(0x05, static_cast<std::uint8_t>(seq));
    const Buffer body = frame_body(f);
    const std::uint8_t hi = body[8], lo = body[9];
    if (hi != 0x7E && hi != 0x7D && lo != 0x7E && lo != 0x7D) continue;
    found = true;
    const Buffer wire = encode(f);
    EXPECT_EQ(wire.size(), 13u);  // 12 + one escape
    const auto d = decode(wire);
    ASSERT_EQ(d.status, DecodeStatus::frame);
    EXPECT_EQ(d.frame, f);
  }
  EXPECT_TRUE(found);
}

TEST(UniclaCodec, ReplyWithPayloadRoundTripsSplitAtEveryByte) {
  Frame f;
  f.source = 0x01;
  f.command = 0xC0;
  f.message_id = 0x01;
  f.sequence = 0x37;
  for (int i = 0; i < 64; ++i) f.payload.push_back(static_cast<std::uint8_t>(0x70 + i % 16));
  const Buffer wire = encode(f);
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const auto d = test::feed_split<Frame>(wire, split, dec);
    ASSERT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, wire.size());
    EXPECT_EQ(d.frame, f);
  }
}

TEST(UniclaCodec, BadChecksum) {
  Buffer wire = {0x7E, 0x00, 0x01, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0xA7, 0x71, 0x7E};
  const auto d = decode(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
  EXPECT_EQ(d.consumed, 11u);  // the closing flag may open the next frame
}

// `wire` decodes as one bad frame (`error`, its first `consumed` bytes), then drive 01's status
// read whole.
void expect_bad_then_status_read(const Buffer& wire, FrameError error, std::size_t consumed) {
  auto d = decode(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, error);
  EXPECT_EQ(d.consumed, consumed);
  d = decode(ByteView(wire).subspan(consumed));
  ASSERT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.frame, status_read(0x01, 0x36));
}

TEST(UniclaCodec, NoiseBeforeAGoodFrame) {
  const Buffer wire = {0x13, 0x00, 0xFF, 0x7E, 0x00, 0x01, 0xC0, 0x01,
                       0x36, 0x00, 0x00, 0x00, 0xA7, 0x70, 0x7E};
  expect_bad_then_status_read(wire, FrameError::bad_header, 3);
}

TEST(UniclaCodec, NoiseWithoutFlagIsDroppedWhole) {
  const Buffer wire = {0x01, 0x02, 0x03};
  const auto d = decode(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_header);
  EXPECT_EQ(d.consumed, 3u);
}

TEST(UniclaCodec, EmptyFrameBetweenFlagsDropsOneFlag) {
  const Buffer wire = {0x7E, 0x7E, 0x00, 0x01, 0xC0, 0x01, 0x36,
                       0x00, 0x00, 0x00, 0xA7, 0x70, 0x7E};
  auto d = decode(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.consumed, 1u);
  d = decode(ByteView(wire).subspan(1));
  ASSERT_EQ(d.status, DecodeStatus::frame);
}

TEST(UniclaCodec, TruncatedFrameThenGoodFrame) {
  // A frame cut short (its tail lost), followed by a whole one.
  const Buffer wire = {0x7E, 0x01, 0x00, 0xC0, 0x7E, 0x00, 0x01, 0xC0,
                       0x01, 0x36, 0x00, 0x00, 0x00, 0xA7, 0x70, 0x7E};
  expect_bad_then_status_read(wire, FrameError::bad_length, 4);
}

TEST(UniclaCodec, PayloadSizeFieldMismatch) {
  Frame f = status_read(0x01, 0x36);
  f.payload = {0x01, 0x02};
  Buffer body = frame_body(f);
  body[7] = 3;  // claims 3 payload bytes, carries 2
  const std::uint16_t crc = crc16(ByteView(body).first(body.size() - 2));
  body[body.size() - 2] = static_cast<std::uint8_t>(crc >> 8);
  body[body.size() - 1] = static_cast<std::uint8_t>(crc);
  const auto d = decode(wrap(body));
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_length);
}

TEST(UniclaCodec, BadEscapes) {
  // 7D followed by a byte that was never stuffed.
  Buffer wire = {0x7E, 0x00, 0x7D, 0x01, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0xA7, 0x70, 0x7E};
  auto d = decode(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_escape);
  // 7D right before the closing flag.
  wire = {0x7E, 0x00, 0x01, 0xC0, 0x01, 0x36, 0x00, 0x00, 0x00, 0xA7, 0x70, 0x7D, 0x7E};
  d = decode(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_escape);
  EXPECT_EQ(d.consumed, 12u);
}

TEST(UniclaCodec, IncompleteUntilEofAndOverlongDropsSof) {
  const Buffer partial = {0x7E, 0x00, 0x01, 0xC0};
  EXPECT_EQ(decode(partial).status, DecodeStatus::incomplete);
  EXPECT_EQ(decode({}).status, DecodeStatus::incomplete);
  Buffer overlong(kMaxWireSize + 1, 0x11);
  overlong[0] = 0x7E;
  const auto d = decode(overlong);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_length);
  EXPECT_EQ(d.consumed, 1u);
}

TEST(UniclaCodec, TooShortBody) {
  const Buffer wire = {0x7E, 0x00, 0x01, 0xC0, 0x01, 0x7E};
  const auto d = decode(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_length);
  EXPECT_EQ(d.consumed, 5u);
}

}  // namespace
}  // namespace drivegate::unicla
