// Golden vectors: every frame printed in the ED3100 document ("Appendix ED3100 communication
// protocol") and in shared/specs/README.md section "ed3100", encoded and decoded.
#include "codec.h"

#include <gtest/gtest.h>

#include "drivegate/crc.h"

#include "feed.h"

namespace drivegate::ed3100 {
namespace {

using drivegate::test::Buffer;
using drivegate::test::feed_split;

Decoded<Reply> reply_of(const Buffer& wire, const ReplyShape& shape) {
  return decode_reply(wire, shape);
}

// Decodes `wire` whole and split at every byte; every way must give the same frame.
void expect_reply_everywhere(const Buffer& wire, const ReplyShape& shape, ReplyKind kind,
                             std::vector<std::uint16_t> words) {
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const auto d = feed_split<Reply>(
        wire, split, [&](std::span<const std::uint8_t> rx) { return decode_reply(rx, shape); });
    ASSERT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, wire.size()) << "split " << split;
    EXPECT_EQ(d.frame.kind, kind);
    EXPECT_EQ(d.frame.address, 0x1F);
    EXPECT_EQ(d.frame.words, words);
  }
}

void expect_request_everywhere(const Buffer& wire, std::uint8_t fn, std::uint16_t reg,
                               std::uint16_t count, std::vector<std::uint16_t> words) {
  for (std::size_t split = 0; split <= wire.size(); ++split) {
    const auto d = feed_split<Request>(
        wire, split, [](std::span<const std::uint8_t> rx) { return decode_request(rx); });
    ASSERT_EQ(d.status, DecodeStatus::frame) << "split " << split;
    EXPECT_EQ(d.consumed, wire.size());
    EXPECT_EQ(d.frame.address, 0x1F);
    EXPECT_EQ(d.frame.function, fn);
    EXPECT_EQ(d.frame.reg, reg);
    EXPECT_EQ(d.frame.count, count);
    EXPECT_EQ(d.frame.words, words);
  }
}

// Document, "03H: read register content", ask frame.
const Buffer kReadParam = {0x1F, 0x03, 0x00, 0x06, 0x00, 0x01, 0x67, 0xB5};
// Same section, feedback frame (register echoed where a byte count belongs).
const Buffer kReadParamReply = {0x1F, 0x03, 0x00, 0x06, 0x10, 0x88, 0xAB, 0xD3};
// Document, "06H: write a data into registers": ask and response are the same frame.
const Buffer kWriteParam = {0x1F, 0x06, 0x00, 0x06, 0x13, 0x88, 0x67, 0x23};
// Document, "10H: write several data continuously": 00-06 = 50.00, 00-07 = 00.01.
const Buffer kWriteTwoParams = {0x1F, 0x10, 0x00, 0x06, 0x00, 0x02, 0x04,
                                0x13, 0x88, 0x00, 0x01, 0x56, 0xC3};
const Buffer kWriteTwoParamsReply = {0x1F, 0x10, 0x00, 0x06, 0x00, 0x02, 0xA2, 0x77};
// Document, "Start forward command ... (continuous operation)"; README: forward, 0x1088.
const Buffer kForward = {0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04,
                         0x00, 0x1E, 0x10, 0x88, 0x67, 0xE6};
// Document, "... (one time run)".
const Buffer kForwardOnce = {0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04,
                             0x00, 0x12, 0x10, 0x88, 0xA7, 0xE5};
// Document, "Reverse run command ... (continuous operation)".
const Buffer kReverse = {0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x04,
                         0x00, 0x2E, 0x10, 0x88, 0x67, 0xE9};
// The response frame of all three run examples.
const Buffer kRunReply = {0x1F, 0x10, 0x20, 0x00, 0x00, 0x02, 0x49, 0xB6};
// Document, "Written stop order": ask and response.
const Buffer kStop = {0x1F, 0x06, 0x20, 0x00, 0x00, 0x01, 0x40, 0x74};
// Document, "read monitoring parameters": ask (retained 00 00) and response.
const Buffer kReadMonitor = {0x1F, 0x03, 0x0D, 0x00, 0x00, 0x00, 0x44, 0xD8};
const Buffer kMonitorReply = {0x1F, 0x03, 0x0D, 0x00, 0x10, 0x84, 0x41, 0x48, 0x47, 0xD5};
// Document, "Read fault code": ask and response.
const Buffer kReadFault = {0x1F, 0x03, 0x0E, 0x01, 0x00, 0x00, 0x15, 0x5C};
const Buffer kFaultReply = {0x1F, 0x03, 0x0E, 0x01, 0xFF, 0xFF, 0x01, 0x48, 0x0F, 0x2B};
// shared/specs/README.md "ed3100": the standard form of a one-word read.
const Buffer kStandardReply = {0x1F, 0x03, 0x02, 0x13, 0x88, 0x1D, 0x10};
// Computed here (this adapter's README): the standard form of the monitor reply above, and
// an "illegal data address" exception to a read.
const Buffer kStandardMonitorReply = {0x1F, 0x03, 0x04, 0x10, 0x84, 0x41, 0x48, 0x70, 0xBD};
const Buffer kReadException = {0x1F, 0x83, 0x02, 0xA0, 0xF7};

TEST(Ed3100Crc, MatchesEveryDocumentFrame) {
  for (const Buffer* f :
       {&kReadParam, &kReadParamReply, &kWriteParam, &kWriteTwoParams, &kWriteTwoParamsReply,
        &kForward, &kForwardOnce, &kReverse, &kRunReply, &kStop, &kReadMonitor, &kMonitorReply,
        &kReadFault, &kFaultReply, &kStandardReply}) {
    const std::uint16_t crc = crc16_modbus(std::span(*f).first(f->size() - 2));
    EXPECT_EQ(crc & 0xFF, (*f)[f->size() - 2]);  // low byte first
    EXPECT_EQ(crc >> 8, (*f)[f->size() - 1]);
  }
}

TEST(Ed3100Encode, DocumentRequests) {
  EXPECT_EQ(encode_read(0x1F, 0x0006, 1), kReadParam);
  EXPECT_EQ(encode_write_single(0x1F, 0x0006, 0x1388), kWriteParam);
  const std::uint16_t two_params[] = {0x1388, 0x0001};
  EXPECT_EQ(encode_write_multiple(0x1F, 0x0006, two_params), kWriteTwoParams);
  const std::uint16_t fwd[] = {0x001E, 0x1088};
  EXPECT_EQ(encode_write_multiple(0x1F, 0x2000, fwd), kForward);
  const std::uint16_t once[] = {0x0012, 0x1088};
  EXPECT_EQ(encode_write_multiple(0x1F, 0x2000, once), kForwardOnce);
  const std::uint16_t rev[] = {0x002E, 0x1088};
  EXPECT_EQ(encode_write_multiple(0x1F, 0x2000, rev), kReverse);
  EXPECT_EQ(encode_write_single(0x1F, 0x2000, 0x0001), kStop);
  EXPECT_EQ(encode_read(0x1F, 0x0D00, 0), kReadMonitor);
  EXPECT_EQ(encode_read(0x1F, 0x0E01, 0), kReadFault);
}

TEST(Ed3100Encode, WriteMultipleTakesOneOrTwoWords) {
  const std::uint16_t three[] = {1, 2, 3};
  EXPECT_TRUE(encode_write_multiple(0x1F, 0x0006, three).empty());
  EXPECT_TRUE(encode_write_multiple(0x1F, 0x0006, {}).empty());
}

TEST(Ed3100Encode, DocumentReplies) {
  const std::uint16_t param[] = {0x1088};
  EXPECT_EQ(encode_read_reply(0x1F, 0x0006, param, ReadForm::document), kReadParamReply);
  const std::uint16_t mon[] = {0x1084, 0x4148};
  EXPECT_EQ(encode_read_reply(0x1F, 0x0D00, mon, ReadForm::document), kMonitorReply);
  EXPECT_EQ(encode_read_reply(0x1F, 0x0D00, mon, ReadForm::standard), kStandardMonitorReply);
  const std::uint16_t fault[] = {0xFFFF, 0x0148};
  EXPECT_EQ(encode_read_reply(0x1F, 0x0E01, fault, ReadForm::document), kFaultReply);
  const std::uint16_t std1[] = {0x1388};
  EXPECT_EQ(encode_read_reply(0x1F, 0x0006, std1, ReadForm::standard), kStandardReply);
  EXPECT_EQ(encode_write_multiple_reply(0x1F, 0x0006, 2), kWriteTwoParamsReply);
  EXPECT_EQ(encode_write_multiple_reply(0x1F, 0x2000, 2), kRunReply);
  EXPECT_EQ(encode_exception(0x1F, 0x03, 0x02), kReadException);
}

TEST(Ed3100DecodeRequest, DocumentRequestsWholeAndSplit) {
  expect_request_everywhere(kReadParam, kFnRead, 0x0006, 1, {});
  expect_request_everywhere(kWriteParam, kFnWriteSingle, 0x0006, 1, {0x1388});
  expect_request_everywhere(kWriteTwoParams, kFnWriteMultiple, 0x0006, 2, {0x1388, 0x0001});
  expect_request_everywhere(kForward, kFnWriteMultiple, 0x2000, 2, {0x001E, 0x1088});
  expect_request_everywhere(kForwardOnce, kFnWriteMultiple, 0x2000, 2, {0x0012, 0x1088});
  expect_request_everywhere(kReverse, kFnWriteMultiple, 0x2000, 2, {0x002E, 0x1088});
  expect_request_everywhere(kStop, kFnWriteSingle, 0x2000, 1, {0x0001});
  expect_request_everywhere(kReadMonitor, kFnRead, 0x0D00, 0, {});
  expect_request_everywhere(kReadFault, kFnRead, 0x0E01, 0, {});
}

TEST(Ed3100DecodeRequest, BadFrames) {
  Buffer bad_crc = kReadParam;
  bad_crc.back() ^= 0x01;
  auto d = decode_request(bad_crc);
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
  EXPECT_EQ(d.consumed, 8u);

  const Buffer unknown_fn = {0x1F, 0x04, 0x00, 0x06, 0x00, 0x01, 0x00, 0x00};
  d = decode_request(unknown_fn);
  EXPECT_EQ(d.error, FrameError::bad_header);
  EXPECT_EQ(d.consumed, 1u);

  Buffer odd_count = kWriteTwoParams;
  odd_count[6] = 0x03;
  d = decode_request(odd_count);
  EXPECT_EQ(d.error, FrameError::bad_length);
  EXPECT_EQ(d.consumed, 1u);

  // Byte count and quantity disagree (CRC recomputed so only the length is wrong).
  Buffer mismatch = {0x1F, 0x10, 0x00, 0x06, 0x00, 0x01, 0x04, 0x13, 0x88, 0x00, 0x01};
  append_crc16_modbus(mismatch);
  d = decode_request(mismatch);
  EXPECT_EQ(d.error, FrameError::bad_length);

  const Buffer truncated(kForward.begin(), kForward.end() - 1);
  EXPECT_EQ(decode_request(truncated).status, DecodeStatus::incomplete);
}

TEST(Ed3100DecodeReply, DocumentFormWholeAndSplit) {
  expect_reply_everywhere(kReadParamReply, {kFnRead, 0x0006, 1}, ReplyKind::read_document,
                          {0x1088});
  expect_reply_everywhere(kMonitorReply, {kFnRead, 0x0D00, 2}, ReplyKind::read_document,
                          {0x1084, 0x4148});
  expect_reply_everywhere(kFaultReply, {kFnRead, 0x0E01, 2}, ReplyKind::read_document,
                          {0xFFFF, 0x0148});
  const auto d = reply_of(kMonitorReply, {kFnRead, 0x0D00, 2});
  EXPECT_EQ(d.frame.reg, 0x0D00);
}

TEST(Ed3100DecodeReply, StandardFormWholeAndSplit) {
  expect_reply_everywhere(kStandardReply, {kFnRead, 0x0006, 1}, ReplyKind::read_standard, {0x1388});
  expect_reply_everywhere(kStandardMonitorReply, {kFnRead, 0x0D00, 2}, ReplyKind::read_standard,
                          {0x1084, 0x4148});
}

TEST(Ed3100DecodeReply, WriteRepliesWholeAndSplit) {
  expect_reply_everywhere(kWriteParam, {kFnWriteSingle, 0x0006, 1}, ReplyKind::write_echo, {});
  expect_reply_everywhere(kStop, {kFnWriteSingle, 0x2000, 1}, ReplyKind::write_echo, {});
  expect_reply_everywhere(kWriteTwoParamsReply, {kFnWriteMultiple, 0x0006, 2},
                          ReplyKind::write_echo, {});
  expect_reply_everywhere(kRunReply, {kFnWriteMultiple, 0x2000, 2}, ReplyKind::write_echo, {});
  const auto d = reply_of(kWriteParam, {kFnWriteSingle, 0x0006, 1});
  EXPECT_EQ(d.frame.reg, 0x0006);
  EXPECT_EQ(d.frame.value, 0x1388);
}

TEST(Ed3100DecodeReply, ExceptionWholeAndSplit) {
  expect_reply_everywhere(kReadException, {kFnRead, 0x0006, 1}, ReplyKind::exception, {});
  EXPECT_EQ(reply_of(kReadException, {kFnRead, 0x0006, 1}).frame.exception, 0x02);
}

TEST(Ed3100DecodeReply, FormsToldApartByCrcWhenTheRegisterLooksLikeACount) {
  // Parameter 02-03 read one word: in the document's form byte 2 (0x02) equals the standard
  // byte count of one word, so only the CRC tells the two apart.
  const std::uint16_t w[] = {0x0005};
  const Buffer doc = encode_read_reply(0x1F, 0x0203, w, ReadForm::document);
  const Buffer std_form = encode_read_reply(0x1F, 0x0203, w, ReadForm::standard);
  ASSERT_EQ(doc[2], 0x02);
  expect_reply_everywhere(doc, {kFnRead, 0x0203, 1}, ReplyKind::read_document, {0x0005});
  expect_reply_everywhere(std_form, {kFnRead, 0x0203, 1}, ReplyKind::read_standard, {0x0005});
}

TEST(Ed3100DecodeReply, BadChecksum) {
  Buffer bad = kMonitorReply;
  bad[9] ^= 0xFF;
  const auto d = reply_of(bad, {kFnRead, 0x0D00, 2});
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_checksum);
  EXPECT_EQ(d.consumed, bad.size());

  Buffer bad_echo = kRunReply;
  bad_echo[6] ^= 0x01;
  EXPECT_EQ(reply_of(bad_echo, {kFnWriteMultiple, 0x2000, 2}).error, FrameError::bad_checksum);

  Buffer bad_exc = kReadException;
  bad_exc[4] ^= 0x01;
  EXPECT_EQ(reply_of(bad_exc, {kFnRead, 0x0006, 1}).error, FrameError::bad_checksum);
}

TEST(Ed3100DecodeReply, BadHeaderSkipsOneByte) {
  // A reply to another function (here a 06 echo while a 03 is awaited).
  const auto d = reply_of(kWriteParam, {kFnRead, 0x0006, 1});
  EXPECT_EQ(d.status, DecodeStatus::bad);
  EXPECT_EQ(d.error, FrameError::bad_header);
  EXPECT_EQ(d.consumed, 1u);
}

TEST(Ed3100DecodeReply, TruncationIsIncomplete) {
  for (std::size_t n = 0; n < kFaultReply.size(); ++n) {
    const Buffer part(kFaultReply.begin(), kFaultReply.begin() + static_cast<long>(n));
    EXPECT_EQ(reply_of(part, {kFnRead, 0x0E01, 2}).status, DecodeStatus::incomplete) << n;
  }
}

TEST(Ed3100DecodeReply, NoiseBeforeAGoodFrameIsSkipped) {
  Buffer wire = {0xAA, 0x55};
  wire.insert(wire.end(), kReadParamReply.begin(), kReadParamReply.end());
  std::span<const std::uint8_t> rx(wire);
  int skipped = 0;
  Decoded<Reply> d;
  while ((d = decode_reply(rx, {kFnRead, 0x0006, 1})).status == DecodeStatus::bad) {
    rx = rx.subspan(d.consumed);
    ++skipped;
  }
  EXPECT_EQ(skipped, 2);
  ASSERT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.frame.words, std::vector<std::uint16_t>{0x1088});
}

TEST(Ed3100DecodeReply, ForeignAddressIsDecodedWithItsAddress) {
  const std::uint16_t w[] = {0x1088};
  const Buffer other = encode_read_reply(0x05, 0x0006, w, ReadForm::document);
  const auto d = reply_of(other, {kFnRead, 0x0006, 1});
  ASSERT_EQ(d.status, DecodeStatus::frame);
  EXPECT_EQ(d.frame.address, 0x05);  // the driver judges it foreign
}

}  // namespace
}  // namespace drivegate::ed3100
