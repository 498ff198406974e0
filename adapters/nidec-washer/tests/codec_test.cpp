// Golden vectors of the Nidec washer protocol (spec V07, read with shared/specs/README.md).
#include "codec.h"

#include <gtest/gtest.h>

#include "feed.h"

namespace drivegate::nidec {
namespace {

using test::Buffer;

Decoded<Reply> reply_at(const Buffer& wire, std::size_t split) {
  return test::feed_split<Reply>(wire, split, [](ByteView rx) { return decode_reply(rx); });
}
Decoded<Request> request_at(const Buffer& wire, std::size_t split) {
  return test::feed_split<Request>(wire, split, [](ByteView rx) { return decode_request(rx); });
}

// A master frame must encode to `wire` and decode back, whole and split at every byte.
void expect_request(const Request& r, const Buffer& wire) {
  EXPECT_EQ(encode(r), wire);
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const Decoded<Request> d = request_at(wire, split);
    ASSERT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, wire.size());
    EXPECT_EQ(d.frame, r);
  }
}

Decoded<Reply> expect_reply(const Buffer& wire) {
  for (std::size_t split = 0; split < wire.size(); ++split) {
    const Decoded<Reply> d = reply_at(wire, split);
    EXPECT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, wire.size()) << "split " << split;
    EXPECT_EQ(encode(d.frame), wire);
  }
  return decode_reply(wire);
}

// A run with a bad XOR must answer bad / bad_checksum and drop exactly `dropped` bytes, whole
// and split at every byte.
template <class Frame>
void expect_bad_checksum(const Buffer& wire, std::size_t dropped,
                         Decoded<Frame> (*decode)(ByteView)) {
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const Decoded<Frame> d = test::feed_split<Frame>(wire, split, decode);
    EXPECT_EQ(d.status, DecodeStatus::bad) << "split " << split;
    EXPECT_EQ(d.error, make_error_code(FrameError::bad_checksum)) << "split " << split;
    EXPECT_EQ(d.consumed, dropped) << "split " << split;
  }
}

// A damaged frame, then a good one that starts inside it: the first decode drops only the
// `dropped` bytes before the good frame's header, and what is left decodes, whole and split at
// every byte, to that frame.
template <class Frame>
Frame expect_resync(const Buffer& wire, std::size_t dropped, Decoded<Frame> (*decode)(ByteView)) {
  expect_bad_checksum(wire, dropped, decode);
  const Buffer rest(wire.begin() + static_cast<long>(dropped), wire.end());
  for (std::size_t split = 0; split <= rest.size(); ++split) {
    const Decoded<Frame> d = test::feed_split<Frame>(rest, split, decode);
    EXPECT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, rest.size()) << "split " << split;
  }
  return decode(rest).frame;
}

// README vectors (shared/specs/README.md, nidec-washer), each recomputed there.
TEST(NidecCodec, PollRequestVector_5_2) {
  expect_request(make_bare(Mode::request),
                 {0xA5, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0});
}

TEST(NidecCodec, StopVector_5_7) {
  expect_request(make_bare(Mode::stop),
                 {0xA5, 0x27, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x82});
}

TEST(NidecCodec, FctVector_5_15) {
  expect_request(make_fct(), {0xA5, 0x66, 0x12, 0x00, 0x34, 0x00, 0x56, 0x00, 0x78, 0x00, 0xCB});
}

TEST(NidecCodec, Cw800rpm3sVector_5_3) {
  expect_request(make_run(Mode::cw, 800, 30),
                 {0xA5, 0x09, 0x03, 0x20, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x91});
}

TEST(NidecCodec, NackVector_5_16) {
  const Buffer wire = {0x5A, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0x5A};
  EXPECT_EQ(encode_nack(), wire);
  const Decoded<Reply> d = expect_reply(wire);
  EXPECT_TRUE(d.frame.nack);
}

// Vectors of this adapter's README, laid out per the section cited, checksums by hand.
TEST(NidecCodec, OtherMasterFrames) {
  // 5.1: platform 7, empty raw weight 0x012C
  expect_request(make_ping(7, 0x012C),
                 {0xA5, 0x02, 0x07, 0x01, 0x2C, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8D});
  // 5.4: CCW 800 rpm, 3.0 s
  expect_request(make_run(Mode::ccw, 800, 30),
                 {0xA5, 0x0B, 0x03, 0x20, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x93});
  // 5.5: agitation 60 rpm, 0.5 s accel/decel, 1.2 s on, 0.8 s off each way
  expect_request(make_agitation(60, {5, 5, 12, 8, 12, 8}),
                 {0xA5, 0x0C, 0x00, 0x3C, 0x05, 0x05, 0x0C, 0x08, 0x0C, 0x08, 0x95});
  // 5.6: spin 1200 rpm, 3.0 s
  expect_request(make_run(Mode::spin, 1200, 30),
                 {0xA5, 0x0D, 0x04, 0xB0, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x02});
  // 5.8, 5.9, 5.10, 5.11: bare commands
  expect_request(make_bare(Mode::brake),
                 {0xA5, 0x29, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8C});
  expect_request(make_bare(Mode::voltage_detection),
                 {0xA5, 0x2B, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8E});
  expect_request(make_bare(Mode::weight_detection),
                 {0xA5, 0x2C, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x89});
  expect_request(make_bare(Mode::fabric_detection),
                 {0xA5, 0x2D, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x88});
  // 5.13: forced brake enable
  expect_request(make_forced_brake(true),
                 {0xA5, 0x1B, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xBF});
  // 5.14: free-shaft spin 1500 rpm, 5.0 s
  expect_request(make_run(Mode::free_shaft_spin, 1500, 50),
                 {0xA5, 0x1D, 0x05, 0xDC, 0x00, 0x32, 0x00, 0x00, 0x00, 0x00, 0x53});
}

TEST(NidecCodec, RequestAck_5_2) {
  // error 0, 800 rpm, 3.5 kg
  const Decoded<Reply> d = expect_reply({0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA0});
  EXPECT_EQ(d.frame.mode, Mode::request);
  EXPECT_EQ(d.frame.error(), 0);
  EXPECT_EQ(d.frame.u16(1), 800);
  EXPECT_EQ(d.frame.data[3], 0x23);
}

TEST(NidecCodec, PingAck_5_1) {
  const Decoded<Reply> d = expect_reply({0xA5, 0x02, 0x07, 0x01, 0x07, 0x00, 0xA6});
  EXPECT_EQ(d.frame.mode, Mode::ping);
  EXPECT_EQ(d.frame.data[0], 7);
  EXPECT_EQ(d.frame.u16(1), 0x0107);
}

TEST(NidecCodec, ErrorBitsInCwAck_5_3_and_8) {
  // stall 0x08 at 800 rpm
  const Decoded<Reply> d = expect_reply({0xA5, 0x09, 0x08, 0x03, 0x20, 0x00, 0x87});
  EXPECT_EQ(d.frame.error(), 0x08);
}

TEST(NidecCodec, VoltageAndWeightAcks_5_9_5_10) {
  EXPECT_EQ(expect_reply({0xA5, 0x2B, 0x00, 0x01, 0x37, 0x00, 0xB8}).frame.u16(1), 311);
  const Decoded<Reply> w = expect_reply({0xA5, 0x2C, 0x00, 0x05, 0x1C, 0x23, 0xB3});
  EXPECT_EQ(w.frame.u16(1), 1308);
  EXPECT_EQ(w.frame.data[3], 35);
}

TEST(NidecCodec, FctAckIsThirteenBytes_5_15) {
  const Buffer wire = {0xA5, 0x66, 0x00, 0x08, 0x00, 0x00, 0x00,
                       0x2D, 0x11, 0x37, 0x00, 0x00, 0xC0};
  const Decoded<Reply> d = expect_reply(wire);
  EXPECT_EQ(d.frame.size, 10);
  EXPECT_EQ(d.frame.u16(0), 0x0008);
  EXPECT_EQ(d.frame.u16(4), 45);
  EXPECT_EQ(d.frame.data[6], 0x11);
  EXPECT_EQ(d.frame.data[7], 0x37);
  EXPECT_EQ(encode_fct_reply({0x00, 0x08, 0x00, 0x00, 0x00, 0x2D, 0x11, 0x37, 0x00, 0x00}), wire);
  // Seven bytes of it are not a frame yet.
  EXPECT_EQ(decode_reply(ByteView(wire).first(7)).status, DecodeStatus::incomplete);
}

TEST(NidecCodec, BadChecksum) {
  const Buffer wire = {0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA1};
  const Decoded<Reply> d = decode_reply(wire);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(d.consumed, 7u);
  const Buffer nack = {0x5A, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0x5B};
  EXPECT_EQ(decode_reply(nack).error, make_error_code(FrameError::bad_checksum));
  Buffer poll = encode(make_bare(Mode::request));
  poll[10] ^= 0x01;
  EXPECT_EQ(decode_request(poll).error, make_error_code(FrameError::bad_checksum));
  EXPECT_EQ(decode_request(poll).consumed, 11u);
}

// Resynchronisation after a bad XOR: only the bytes before the next frame start are dropped.
TEST(NidecCodec, BadChecksumResyncsOnAnAckInside_4_2) {
  // The request ACK of 5.2 (800 rpm, 3.5 kg) lost its byte 4 (03); the next request ACK's A5
  // falls at offset 6 of the first seven bytes.
  Reply r = expect_resync<Reply>({0xA5, 0x05, 0x00, 0x20, 0x23, 0xA0,  //
                                  0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA0},
                                 6, decode_reply);
  EXPECT_EQ(r.mode, Mode::request);
  EXPECT_EQ(r.u16(1), 800);
  // A reply cut short after three bytes: the good one's A5 is at offset 3.
  r = expect_resync<Reply>({0xA5, 0x05, 0x00,  //
                            0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA0},
                           3, decode_reply);
  EXPECT_EQ(r.u16(1), 800);
  EXPECT_EQ(r.data[3], 0x23);
}

TEST(NidecCodec, BadChecksumResyncsOnANackHeaderToo_4_2_5_16) {
  // 4.2: a slave frame starts A5, or 5A for the NACK; both are frame starts.
  EXPECT_TRUE(expect_resync<Reply>({0xA5, 0x05, 0x00,  //
                                    0x5A, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0x5A},
                                   3, decode_reply)
                  .nack);
  const Reply r = expect_resync<Reply>({0x5A, 0x00, 0xFF,  //
                                        0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA0},
                                       3, decode_reply);
  EXPECT_FALSE(r.nack);
  EXPECT_EQ(r.u16(1), 800);
}

TEST(NidecCodec, BadChecksumResyncsInsideAnFctAck_5_15) {
  // Five bytes of an FCT ACK, then the whole FCT ACK: the 13 bytes examined hold its A5 at 5.
  const Reply r = expect_resync<Reply>(
      {0xA5, 0x66, 0x00, 0x08, 0x00,  //
       0xA5, 0x66, 0x00, 0x08, 0x00, 0x00, 0x00, 0x2D, 0x11, 0x37, 0x00, 0x00, 0xC0},
      5, decode_reply);
  EXPECT_EQ(r.mode, Mode::fct_test);
  EXPECT_EQ(r.size, 10);
  EXPECT_EQ(r.u16(4), 45);
}

TEST(NidecCodec, BadChecksumResyncsOnAMasterFrameInside_4_1) {
  // Four bytes of a poll (5.2), then the Stop vector of 5.7.
  const Request r =
      expect_resync<Request>({0xA5, 0x05, 0x00, 0x00,  //
                              0xA5, 0x27, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x82},
                             4, decode_request);
  EXPECT_EQ(r, make_bare(Mode::stop));
  // 4.1: a master frame starts A5 only, so a 5A inside one (platform 0x5A, 5.1) is no restart.
  Buffer ping = encode(make_ping(0x5A, 0));
  ASSERT_EQ(ping, Buffer({0xA5, 0x02, 0x5A, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xFD}));
  ping[10] ^= 0x01;
  expect_bad_checksum<Request>(ping, 11, decode_request);
}

TEST(NidecCodec, BadChecksumWithoutAFrameStartInsideIsDroppedWhole) {
  // 4.2 request ACK, 5.16 NACK, 5.15 FCT ACK, 4.1 poll, each with its XOR flipped.
  expect_bad_checksum<Reply>({0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA1}, 7, decode_reply);
  expect_bad_checksum<Reply>({0x5A, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0x5B}, 7, decode_reply);
  expect_bad_checksum<Reply>(
      {0xA5, 0x66, 0x00, 0x08, 0x00, 0x00, 0x00, 0x2D, 0x11, 0x37, 0x00, 0x00, 0xC1}, 13,
      decode_reply);
  expect_bad_checksum<Request>({0xA5, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA1},
                               11, decode_request);
}

TEST(NidecCodec, FrameStartsInsideFramesOnlyMatterOnABadChecksum_4_2) {
  // 5.2: a weight of 0xA5 (16.5 kg) in a good request ACK is data, the frame decodes whole.
  const Decoded<Reply> d = expect_reply({0xA5, 0x05, 0x00, 0x03, 0x20, 0xA5, 0x26});
  EXPECT_EQ(d.frame.data[3], 0xA5);
  // A bad XOR byte that happens to be A5 is where the next frame may start: six bytes go, and
  // the lone A5 left waits for more.
  const Buffer wire = {0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA5};
  expect_bad_checksum<Reply>(wire, 6, decode_reply);
  EXPECT_EQ(decode_reply(ByteView(wire).subspan(6)).status, DecodeStatus::incomplete);
}

TEST(NidecCodec, BadHeader) {
  const Buffer wire = {0x00, 0xA5, 0x05};
  const Decoded<Reply> d = decode_reply(wire);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_header));
  EXPECT_EQ(d.consumed, 1u);
  EXPECT_EQ(decode_request(wire).error, make_error_code(FrameError::bad_header));
}

TEST(NidecCodec, RemovedClutchingAndUnknownModesAreBadFields) {
  // 0x19 was removed in V07 (section 1, 5.12).
  const Buffer clutch_ack = {0xA5, 0x19, 0x00, 0x00, 0x00, 0x01, 0xBD};
  const Decoded<Reply> d = decode_reply(clutch_ack);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, make_error_code(FrameError::bad_field));
  EXPECT_EQ(d.consumed, 1u);
  Request clutch{static_cast<Mode>(0x19), {1}};
  const Decoded<Request> r = decode_request(encode(clutch));
  EXPECT_EQ(r.error, make_error_code(FrameError::bad_field));
  EXPECT_EQ(r.consumed, 11u);
}

TEST(NidecCodec, TruncatedIsIncomplete) {
  const Buffer wire = {0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA0};
  for (std::size_t n = 0; n < wire.size(); ++n) {
    EXPECT_EQ(decode_reply(ByteView(wire).first(n)).status, DecodeStatus::incomplete) << n;
  }
  const Buffer poll = encode(make_bare(Mode::request));
  EXPECT_EQ(decode_request(ByteView(poll).first(10)).status, DecodeStatus::incomplete);
}

TEST(NidecCodec, NoiseBeforeAGoodFrameResynchronises) {
  const Buffer wire = {0x00, 0xFF, 0x13, 0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA0};
  ByteView rx(wire);
  int dropped = 0;
  for (;;) {
    const Decoded<Reply> d = decode_reply(rx);
    ASSERT_NE(d.status, DecodeStatus::incomplete);
    ASSERT_GT(d.consumed, 0u);
    if (d.status == DecodeStatus::frame) {
      EXPECT_EQ(d.frame.u16(1), 800);
      EXPECT_EQ(d.consumed, rx.size());
      break;
    }
    dropped += static_cast<int>(d.consumed);
    rx = rx.subspan(d.consumed);
  }
  EXPECT_EQ(dropped, 3);
}

TEST(NidecCodec, XorOfAllFrameBytes_4_1) {
  const Buffer b = {0xA5, 0x09, 0x03, 0x20, 0x00, 0x1E};
  EXPECT_EQ(xor_of(b), 0x91);
  EXPECT_EQ(xor_of({}), 0x00);
}

}  // namespace
}  // namespace drivegate::nidec
