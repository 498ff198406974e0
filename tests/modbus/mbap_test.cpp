// MBAP framing (Modbus Messaging on TCP/IP Implementation Guide V1.0b, 3.1.3; Application
// Protocol V1.1b3, 4.1 for the 253-byte PDU limit), table-driven.
#include "mbap.h"

#include <gtest/gtest.h>

#include <vector>

namespace drivegate::modbus::mbap_test {
namespace {

using Bytes = std::vector<std::uint8_t>;
using Status = MbapParse::Status;

MbapParse parse(const Bytes& b) {
  return parse_mbap(std::span<const std::uint8_t>(b));
}

// A header with the given protocol id and length, followed by `body` bytes (unit id + PDU).
Bytes frame(std::uint16_t protocol, std::uint16_t length, std::size_t body) {
  Bytes b{0x12,
          0x34,
          static_cast<std::uint8_t>(protocol >> 8),
          static_cast<std::uint8_t>(protocol),
          static_cast<std::uint8_t>(length >> 8),
          static_cast<std::uint8_t>(length)};
  for (std::size_t i = 0; i < body; ++i) b.push_back(i == 0 ? 0x01 : 0x03);
  return b;
}

struct Case {
  const char* name;
  Bytes wire;
  Status status;
  std::error_code error;
  std::size_t consumed;
};
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.name;
}

class MbapTable : public ::testing::TestWithParam<Case> {};

TEST_P(MbapTable, WholeAndSplitAtEveryByte) {
  const Case& c = GetParam();
  const auto whole = parse(c.wire);
  EXPECT_EQ(whole.status, c.status);
  EXPECT_EQ(whole.error, c.error);
  EXPECT_EQ(whole.consumed, c.consumed);
  // A receive buffer that grows one byte at a time: every prefix before the deciding byte is
  // indeterminate, and the verdict never changes once reached.
  bool decided = false;
  for (std::size_t n = 0; n <= c.wire.size(); ++n) {
    const Bytes prefix(c.wire.begin(), c.wire.begin() + static_cast<long>(n));
    const auto r = parse(prefix);
    if (r.status == Status::indeterminate) {
      EXPECT_FALSE(decided) << "prefix " << n;
      continue;
    }
    decided = true;
    EXPECT_EQ(r.status, c.status) << "prefix " << n;
    EXPECT_EQ(r.error, c.error) << "prefix " << n;
  }
}

INSTANTIATE_TEST_SUITE_P(
    ImplementationGuide313, MbapTable,
    ::testing::Values(
        // Application Protocol 6.3 example request (03 00 6B 00 03) for unit 0x11.
        Case{"read_holding",
             {0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x11, 0x03, 0x00, 0x6B, 0x00, 0x03},
             Status::good,
             {},
             12},
        Case{"protocol_id_1", frame(0x0001, 6, 6), Status::bad, MbapError::bad_protocol_id, 0},
        Case{"protocol_id_ffff", frame(0xFFFF, 6, 6), Status::bad, MbapError::bad_protocol_id, 0},
        Case{"length_0", frame(0, 0, 0), Status::bad, MbapError::length_zero, 0},
        Case{"length_1_no_function", frame(0, 1, 1), Status::bad, MbapError::empty_pdu, 0},
        Case{"length_2_smallest", frame(0, 2, 2), Status::good, {}, 8},
        Case{"length_254_largest", frame(0, 254, 254), Status::good, {}, 260},
        Case{"length_255", frame(0, 255, 255), Status::bad, MbapError::length_too_long, 0},
        Case{"length_65535", frame(0, 65535, 10), Status::bad, MbapError::length_too_long, 0},
        Case{"truncated", frame(0, 6, 5), Status::indeterminate, {}, 0}),
    [](const auto& p) { return std::string(p.param.name); });

TEST(Mbap, GoodFrameExposesHeaderAndPdu) {
  const Bytes wire{0xAB, 0xCD, 0x00, 0x00, 0x00, 0x06, 0x11, 0x03, 0x00, 0x6B, 0x00, 0x03};
  const auto r = parse(wire);
  ASSERT_EQ(r.status, Status::good);
  EXPECT_EQ(r.header.transaction, 0xABCD);
  EXPECT_EQ(r.header.protocol, 0);
  EXPECT_EQ(r.header.length, 6);
  EXPECT_EQ(r.header.unit, 0x11);
  EXPECT_EQ(Bytes(r.pdu.begin(), r.pdu.end()), (Bytes{0x03, 0x00, 0x6B, 0x00, 0x03}));
}

TEST(Mbap, SeveralRequestsInOneSegment) {
  Bytes wire;
  for (std::uint8_t t = 0; t < 3; ++t) {
    const Bytes one{0x00, t, 0x00, 0x00, 0x00, 0x06, 0x01, 0x04, 0x00, t, 0x00, 0x01};
    wire.insert(wire.end(), one.begin(), one.end());
  }
  wire.insert(wire.end(), {0x00, 0x09, 0x00});  // and the start of a fourth
  std::span<const std::uint8_t> rest(wire);
  for (std::uint8_t t = 0; t < 3; ++t) {
    const auto r = parse_mbap(rest);
    ASSERT_EQ(r.status, Status::good);
    EXPECT_EQ(r.header.transaction, t);
    EXPECT_EQ(r.pdu[2], t);
    rest = rest.subspan(r.consumed);
  }
  EXPECT_EQ(parse_mbap(rest).status, Status::indeterminate);
}

TEST(Mbap, RequestLongerThanAnnouncedEndsAtTheLength) {
  // Length 6 announced, 8 bytes of PDU sent: the frame ends where the length says; the two extra
  // bytes start the next frame, here one whose protocol id is not 0.
  const Bytes wire{0x00, 0x01, 0x00, 0x00, 0x00, 0x06, 0x01, 0x03,
                   0x00, 0x00, 0x00, 0x01, 0xAA, 0xBB, 0xCC, 0xDD};
  const auto r = parse(wire);
  ASSERT_EQ(r.status, Status::good);
  EXPECT_EQ(r.consumed, 12u);
  EXPECT_EQ(r.pdu.size(), 5u);
  const auto next = parse_mbap(std::span<const std::uint8_t>(wire).subspan(r.consumed));
  EXPECT_EQ(next.status, Status::bad);
  EXPECT_EQ(next.error, MbapError::bad_protocol_id);
}

TEST(Mbap, PutMbapWritesTheResponseHeader) {
  std::array<std::uint8_t, 7> h{};
  put_mbap(h, 0xBEEF, 0x11, 9);
  EXPECT_EQ(h, (std::array<std::uint8_t, 7>{0xBE, 0xEF, 0x00, 0x00, 0x00, 0x0A, 0x11}));
}

TEST(Mbap, ErrorsHaveMessages) {
  EXPECT_EQ(std::error_code(MbapError::bad_protocol_id).category().name(), std::string("mbap"));
  EXPECT_NE(std::error_code(MbapError::length_too_long).message(), "unknown MBAP error");
}

}  // namespace
}  // namespace drivegate::modbus::mbap_test
