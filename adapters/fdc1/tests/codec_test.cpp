// Golden vectors: the speed frame is the specs README's ("fdc1 (003)": 2000..3000 rpm gives
// x = 10). The document prints no other whole frame; the status and programming vectors below
// were worked out by hand (python, not this codec) from the OUTPUT and INPUT tables and are
// repeated in adapters/fdc1/README.md.
#include "codec.h"

#include <gtest/gtest.h>

#include "feed.h"

namespace drivegate::fdc1 {
namespace {

using test::Buffer;

// specs README, fdc1: 72 115 07 208 11 184 85 x, x = 10.
const Buffer kSpeed2000to3000 = {0x48, 0x73, 0x07, 0xD0, 0x0B, 0xB8, 0x55, 0x0A};
// OUTPUT, motor ON: 2500 rpm = 09 C4, 2.5 A x 3160 = 7900 = 1E DC; co = 1B^09^1E, ce = 4C^C4^DC.
const Buffer kOn2500 = {0x1B, 0x4C, 0x09, 0xC4, 0x1E, 0xDC, 0x0C, 0x54};
// OUTPUT, motor OFF: alarm 48 (motor failed to start), 10 s x 122 = 1220 = 04 C4.
const Buffer kOffStall10s = {0x1B, 0x4C, 0x00, 0x30, 0x04, 0xC4, 0x1F, 0xB8};
// OUTPUT, motor OFF, no alarm, no wait.
const Buffer kOffIdle = {0x1B, 0x4C, 0x00, 0x00, 0x00, 0x00, 0x1B, 0x4C};
// INPUT programming, standard: 2000..3000 rpm, mode 2 (slave), 10.5/12.5, 21/25, 36/44 V, each
// x 1187 rounded: 12464 14838 24927 29675 42732 52228.
const Buffer kProgramStandard = {0x48, 0x50, 0x07, 0xD0, 0x0B, 0xB8, 0x00, 0x02, 0x30, 0xB0, 0x39,
                                 0xF6, 0x61, 0x5F, 0x73, 0xEB, 0xA6, 0xEC, 0xCC, 0x04, 0x35, 0x20};
// INPUT programming, special: 1800..3200 rpm, mode 34 (slave + special), 10.0 / 11.6 V
// (11870 / 13769), bytes 13..18 = 255, nominal 14.0 V (16618).
const Buffer kProgramSpecial = {0x48, 0x50, 0x07, 0x08, 0x0C, 0x80, 0x00, 0x22, 0x2E, 0x5E, 0x35,
                                0xC9, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x40, 0xEA, 0xE7, 0x78};

Program standard_program() {
  return {2000, 3000, 0, 2, {12464, 14838, 24927, 29675, 42732, 52228}};
}

Buffer echo_of(Buffer frame) {
  frame[0] = 27;  // INPUT programming: "except for the first two bytes (27 and 80)"
  frame[1] = 80;
  return frame;
}

// `wire` decodes as `want` however it is split between two reads.
template <class Frame>
void expect_decoded(const Buffer& wire, const Frame& want, Decoded<Frame> (*decode)(ByteView)) {
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    SCOPED_TRACE(split);
    const auto d = test::feed_split<Frame>(wire, split, decode);
    ASSERT_EQ(d.status, DecodeStatus::frame);
    EXPECT_EQ(d.consumed, wire.size());
    EXPECT_EQ(d.frame, want);
  }
}
void expect_device(const Buffer& wire, const DeviceFrame& want) {
  expect_decoded(wire, want, decode_device);
}
void expect_master(const Buffer& wire, const MasterFrame& want) {
  expect_decoded(wire, want, decode_master);
}

TEST(Fdc1Codec, SpeedGoldenVectorFromSpecsReadme) {
  EXPECT_EQ(encode_speed({2000, 3000}), kSpeed2000to3000);
  EXPECT_EQ(xor_all(ByteView(kSpeed2000to3000).first(7)), 10);  // "gives x = 10"
  expect_master(kSpeed2000to3000, Speed{2000, 3000});
}

TEST(Fdc1Codec, SlaveSpeedFrames) {
  // INPUT speed, SLAVE MODE: min = max = 2000 to run, min 0 (max 3500) to stop.
  EXPECT_EQ(encode_speed({2000, 2000}), (Buffer{0x48, 0x73, 0x07, 0xD0, 0x07, 0xD0, 0x55, 0x6E}));
  EXPECT_EQ(encode_speed({0, 3500}), (Buffer{0x48, 0x73, 0x00, 0x00, 0x0D, 0xAC, 0x55, 0xCF}));
}

TEST(Fdc1Codec, StatusOnForm) {
  const Status s{true, 2500, 0, 7900};
  EXPECT_EQ(encode_status(s), kOn2500);
  expect_device(kOn2500, s);
  EXPECT_DOUBLE_EQ(s.current_a(), 2.5);
  EXPECT_DOUBLE_EQ(s.restart_s(), 0.0);
}

TEST(Fdc1Codec, StatusOffForm) {
  const Status s{false, 0, 0x30, 1220};
  EXPECT_EQ(encode_status(s), kOffStall10s);
  expect_device(kOffStall10s, s);
  EXPECT_DOUBLE_EQ(s.restart_s(), 10.0);
  EXPECT_DOUBLE_EQ(s.current_a(), 0.0);
  EXPECT_EQ(encode_status(Status{}), kOffIdle);
  expect_device(kOffIdle, Status{});
}

TEST(Fdc1Codec, StatusChecksumPairIsOddAndEvenBytes) {
  // OUTPUT: checksum_odd = byte_1 ^ byte_3 ^ byte_5, checksum_even = byte_2 ^ byte_4 ^ byte_6.
  const auto sum = xor_pair(ByteView(kOn2500).first(6));
  EXPECT_EQ(sum[0], 0x1B ^ 0x09 ^ 0x1E);
  EXPECT_EQ(sum[1], 0x4C ^ 0xC4 ^ 0xDC);
}

TEST(Fdc1Codec, ProgramStandardGolden) {
  EXPECT_EQ(encode_program(standard_program()), kProgramStandard);
  expect_master(kProgramStandard, standard_program());
}

TEST(Fdc1Codec, ProgramSpecialGolden) {
  const Program p{1800, 3200, 0, 34, {11870, 13769, 0xFFFF, 0xFFFF, 0xFFFF, 16618}};
  EXPECT_EQ(encode_program(p), kProgramSpecial);
  expect_master(kProgramSpecial, p);
}

TEST(Fdc1Codec, EchoKeepsTheSentChecksums) {
  // INPUT programming: the device returns "the same sequence of bytes ... except for the first
  // two bytes": the checksums stay those computed over 72 80.
  const Buffer echo = echo_of(kProgramStandard);
  EXPECT_EQ(encode_echo(standard_program()), echo);
  expect_device(echo, Echo{standard_program()});
}

TEST(Fdc1Codec, EchoWithRecomputedChecksumIsAcceptedToo) {
  Buffer echo = echo_of(kProgramStandard);
  echo[20] = 0x35 ^ 0x48 ^ 0x1B;  // checksum_odd over 27 instead of 72
  expect_device(echo, Echo{standard_program()});
}

TEST(Fdc1Codec, EveryPrefixIsIncomplete) {
  for (const Buffer* wire : {&kOn2500, &kProgramStandard}) {
    for (std::size_t n = 0; n < wire->size(); ++n) {
      SCOPED_TRACE(n);
      const Buffer prefix(wire->begin(), wire->begin() + static_cast<long>(n));
      if (wire == &kOn2500) {
        EXPECT_EQ(decode_device(prefix).status, DecodeStatus::incomplete);
      } else {
        EXPECT_EQ(decode_master(prefix).status, DecodeStatus::incomplete);
      }
    }
  }
}

TEST(Fdc1Codec, BadStatusChecksumResynchronisesOnTheNextHeader) {
  Buffer wire = kOn2500;
  wire[7] ^= 0x01;
  wire.insert(wire.end(), kOffIdle.begin(), kOffIdle.end());
  const auto d = decode_device(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
  // kOn2500 holds no other 1B: everything up to the next frame's header goes.
  EXPECT_EQ(d.consumed, 8u);
  const auto next = decode_device(ByteView(wire).subspan(d.consumed));
  ASSERT_EQ(next.status, DecodeStatus::frame);
  EXPECT_EQ(next.frame, DeviceFrame{Status{}});
}

TEST(Fdc1Codec, BadChecksumKeepsAHeaderInsideTheWindow) {
  // A dropped byte: the window of 8 holds the next frame's 1B; only the bytes before it go.
  Buffer wire(kOn2500.begin(), kOn2500.begin() + 5);
  wire.insert(wire.end(), kOffIdle.begin(), kOffIdle.end());
  const auto d = decode_device(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
  EXPECT_EQ(d.consumed, 5u);
}

TEST(Fdc1Codec, BadHeader) {
  const Buffer second_byte_wrong = {0x1B, 0x4D, 0x00, 0x00, 0x00, 0x00, 0x1B, 0x4D};
  auto d = decode_device(second_byte_wrong);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_header);
  EXPECT_EQ(d.consumed, 6u);              // up to the next 1B
  d = decode_device(Buffer{0x48, 0x73});  // the master's header is noise to the master
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.consumed, 2u);
  const auto m = decode_master(Buffer{0x48, 0x74, 0x00});
  ASSERT_EQ(m.status, DecodeStatus::bad);
  EXPECT_EQ(m.error, FrameError::bad_header);
}

TEST(Fdc1Codec, NoiseBeforeAGoodFrame) {
  Buffer wire = {0x00, 0xFF, 0x1B, 0x1B, 0xAA};
  wire.insert(wire.end(), kOn2500.begin(), kOn2500.end());
  std::size_t at = 0;
  int bad = 0;
  for (;;) {
    const auto d = decode_device(ByteView(wire).subspan(at));
    ASSERT_NE(d.status, DecodeStatus::incomplete);
    ASSERT_GT(d.consumed, 0u);
    at += d.consumed;
    if (d.status == DecodeStatus::frame) {
      EXPECT_EQ(d.frame, DeviceFrame{(Status{true, 2500, 0, 7900})});
      break;
    }
    ++bad;
  }
  EXPECT_EQ(at, wire.size());
  EXPECT_EQ(bad, 3);  // 00 FF | 1B (1B follows) | 1B AA
}

TEST(Fdc1Codec, SpeedFrameWithoutThe85IsABadField) {
  Buffer wire = kSpeed2000to3000;
  wire[6] = 0x56;
  wire[7] = xor_all(ByteView(wire).first(7));  // checksum holds, byte 7 does not
  const auto d = decode_master(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_field);
}

TEST(Fdc1Codec, BadProgramChecksums) {
  Buffer wire = kProgramStandard;
  wire[21] ^= 0x80;
  auto d = decode_master(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
  Buffer echo = echo_of(kProgramStandard);
  echo[9] ^= 0x01;  // a data byte: neither checksum reading holds
  const auto e = decode_device(echo);
  ASSERT_EQ(e.status, DecodeStatus::bad);
  EXPECT_EQ(e.error, FrameError::bad_checksum);
}

TEST(Fdc1Codec, BadSpeedChecksum) {
  Buffer wire = kSpeed2000to3000;
  wire[7] = 0x0B;
  const auto d = decode_master(wire);
  ASSERT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
}

}  // namespace
}  // namespace drivegate::fdc1
