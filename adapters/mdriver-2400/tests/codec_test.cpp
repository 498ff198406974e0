// Codec golden vectors (vendor document 002 and shared/specs/README.md) and bad frames.
#include "codec.h"

#include <gtest/gtest.h>

#include "feed.h"

namespace drivegate::mdriver {
namespace {

using test::Buffer;

Decoded<Frame> dec(ByteView b) {
  return decode(b);
}

// Decodes `wire` whole and split at every byte: always the same single frame.
Frame decode_every_split(const Bytes& wire) {
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    SCOPED_TRACE(testing::Message() << "split at " << split);
    const auto d = test::feed_split<Frame>(wire, split, dec);
    EXPECT_EQ(d.status, DecodeStatus::frame);
    EXPECT_EQ(d.consumed, wire.size());
  }
  const auto d = decode(wire);
  EXPECT_EQ(d.status, DecodeStatus::frame);
  return d.frame;
}

// Section 3 No.1 (and README): the fixed-code check, D8 = 38.
const Bytes kCheck{0x00, 0x01, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x38};
// README / section 3 No.2: run 504 rpm (code 1C), normal ramp, D7 = 25.
const Bytes kRun504{0x00, 0x01, 0x10, 0x02, 0x1C, 0x01, 0x00, 0x25};
// Section 3 No.1, the echo R0..R8 (checksum ** in the document; computed: the same bytes as the
// request with the addresses swapped sum alike, 38).
const Bytes kCheckEcho{0x01, 0x00, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x38};
// Section 3 No.1, fixed-code error: R4..R7 = 00 00 00 00 (checksum computed: 55 - 04 = 51).
const Bytes kCheckZeros{0x01, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x00, 0x51};
// Section 3 No.2 reply R0..R12 with target 1C, actual 1C, no error, IPM 1A = 26 deg C (the
// document's example), info 00 (checksum computed: EB).
const Bytes kRunReply{0x01, 0x00, 0x10, 0x07, 0x1C, 0x1C, 0x00, 0x00, 0x1A, 0x00, 0x00, 0x00, 0xEB};

TEST(MdriverCodec, ChecksumMakesTheSum55) {
  EXPECT_EQ(checksum(Bytes{0x00, 0x01, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06}), 0x38);
  EXPECT_EQ(checksum(Bytes{0x00, 0x01, 0x10, 0x02, 0x1C, 0x01, 0x00}), 0x25);
  EXPECT_EQ(checksum(Bytes{}), 0x55);
  EXPECT_EQ(checksum(Bytes{0x56}), 0xFF);  // wraps mod 256
}

TEST(MdriverCodec, FixedCodeCheckGolden) {
  EXPECT_EQ(encode_check(0x00, 0x01), kCheck);
  const Frame f = decode_every_split(kCheck);
  EXPECT_EQ(f.src, 0x00);
  EXPECT_EQ(f.dst, 0x01);
  EXPECT_EQ(f.cmd, 0x00);
  EXPECT_EQ(parse_check(f), kFixedCode);
}

TEST(MdriverCodec, Run504Golden) {
  EXPECT_EQ(encode_run(0x00, 0x01, 0x1C, kChangeNormal), kRun504);
  const auto req = parse_run_request(decode_every_split(kRun504));
  ASSERT_TRUE(req.has_value());
  EXPECT_EQ(req->code, 0x1C);
  EXPECT_EQ(req->change, 0x01);
}

TEST(MdriverCodec, CheckRepliesGolden) {
  EXPECT_EQ(encode_check_reply(0x01, 0x00, kFixedCode), kCheckEcho);
  EXPECT_EQ(encode_check_reply(0x01, 0x00, kFixedCodeError), kCheckZeros);
  EXPECT_EQ(parse_check(decode_every_split(kCheckEcho)), kFixedCode);
  EXPECT_EQ(parse_check(decode_every_split(kCheckZeros)), kFixedCodeError);
}

TEST(MdriverCodec, RunReplyGolden) {
  RunReply r;
  r.target_code = 0x1C;
  r.actual_code = 0x1C;
  r.ipm_temp_c = 0x1A;
  EXPECT_EQ(encode_run_reply(0x01, 0x00, r), kRunReply);
  const Frame f = decode_every_split(kRunReply);
  EXPECT_EQ(f.src, 0x01);
  EXPECT_EQ(f.dst, 0x00);
  EXPECT_EQ(parse_run_reply(f), r);
  EXPECT_FALSE(parse_run_request(f).has_value());  // 8 data bytes: not a request
}

TEST(MdriverCodec, RunReplyAllFields) {
  // Every field at its own place: target 40, actual 40, reserved 00, error 0E, IPM 48 deg C,
  // info 01 02 03 (checksum computed: 79).
  const Bytes wire{0x01, 0x00, 0x10, 0x07, 0x40, 0x40, 0x00, 0x0E, 0x30, 0x01, 0x02, 0x03, 0x79};
  const auto r = parse_run_reply(decode_every_split(wire));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->target_code, 0x40);
  EXPECT_EQ(r->actual_code, 0x40);
  EXPECT_EQ(r->error_code, 0x0E);
  EXPECT_EQ(r->ipm_temp_c, 48);
  EXPECT_EQ(r->info, (std::array<std::uint8_t, 3>{1, 2, 3}));
  EXPECT_EQ(encode_run_reply(0x01, 0x00, *r), wire);
}

TEST(MdriverCodec, ConfigurableAddresses) {
  const Bytes w = encode_check(0x05, 0x22);
  EXPECT_EQ(w, (Bytes{0x05, 0x22, 0x00, 0x03, 0x01, 0x12, 0x00, 0x06, 0x12}));
  const Frame f = decode_every_split(w);
  EXPECT_EQ(f.src, 0x05);
  EXPECT_EQ(f.dst, 0x22);
}

TEST(MdriverCodec, BadChecksumDropsTheWholeFrame) {
  Bytes w = kRunReply;
  w.back() ^= 0x01;
  const auto d = decode(w);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
  EXPECT_EQ(d.consumed, w.size());
}

TEST(MdriverCodec, UnknownCommandIsABadHeader) {
  const Bytes w{0x01, 0x00, 0x20, 0x03, 0x01, 0x12, 0x00, 0x06, 0x18};
  const auto d = decode(w);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_header);
  EXPECT_EQ(d.consumed, 1u);
  // Known as soon as the command byte is there.
  const auto early = decode(ByteView(w).first(3));
  EXPECT_EQ(early.status, DecodeStatus::bad);
}

TEST(MdriverCodec, LengthOverTenDataBytesIsBad) {
  // Section 1 No.6: at most 15 bytes, so D3 <= 09.
  const Bytes w{0x01, 0x00, 0x10, 0x0A};
  const auto d = decode(w);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_length);
  EXPECT_EQ(d.consumed, 1u);
  Bytes ten{0x01, 0x00, 0x10, 0x09, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  ten.push_back(checksum(ten));
  EXPECT_EQ(decode(ten).status, DecodeStatus::frame);
  EXPECT_EQ(ten.size(), kMaxFrame);
}

TEST(MdriverCodec, TruncatedFrameIsIncomplete) {
  for (std::size_t n = 0; n < kRunReply.size(); ++n) {
    const auto d = decode(ByteView(kRunReply).first(n));
    EXPECT_EQ(d.status, DecodeStatus::incomplete) << n;
    EXPECT_EQ(d.consumed, 0u);
  }
}

TEST(MdriverCodec, NoiseBeforeAGoodFrame) {
  Bytes rx{0xFF, 0xFF, 0x33};
  rx.insert(rx.end(), kRunReply.begin(), kRunReply.end());
  std::size_t dropped = 0;
  ByteView view(rx);
  for (;;) {
    const auto d = decode(view);
    ASSERT_NE(d.status, DecodeStatus::incomplete);
    ASSERT_GT(d.consumed, 0u);
    if (d.status == DecodeStatus::frame) {
      EXPECT_EQ(parse_run_reply(d.frame)->ipm_temp_c, 0x1A);
      break;
    }
    dropped += d.consumed;
    view = view.subspan(d.consumed);
  }
  EXPECT_EQ(dropped, 3u);
}

TEST(MdriverCodec, TruncatedFrameThenAGoodOneResynchronises) {
  Bytes rx(kRunReply.begin(), kRunReply.begin() + 6);  // cut after R5
  rx.insert(rx.end(), kRunReply.begin(), kRunReply.end());
  const auto first = decode(rx);
  EXPECT_EQ(first.status, DecodeStatus::bad);
  EXPECT_EQ(first.consumed, 6u);
  const auto second = decode(ByteView(rx).subspan(6));
  EXPECT_EQ(second.status, DecodeStatus::frame);
  EXPECT_EQ(second.consumed, kRunReply.size());
}

TEST(MdriverCodec, ForeignAddressStillDecodes) {
  // The codec is address-blind; the driver calls a frame from another driver foreign.
  const Bytes w = encode_check_reply(0x07, 0x00, kFixedCode);
  const Frame f = decode_every_split(w);
  EXPECT_EQ(f.src, 0x07);
}

TEST(MdriverCodec, WrongLayoutsDoNotParse) {
  const Frame short_check{0x01, 0x00, 0x00, {0x01, 0x12, 0x00}};
  EXPECT_FALSE(parse_check(short_check).has_value());
  const Frame run_as_check{0x01, 0x00, 0x10, {0x01, 0x12, 0x00, 0x06}};
  EXPECT_FALSE(parse_check(run_as_check).has_value());
  EXPECT_FALSE(parse_run_reply(run_as_check).has_value());
  EXPECT_FALSE(parse_run_request(run_as_check).has_value());
}

}  // namespace
}  // namespace drivegate::mdriver
