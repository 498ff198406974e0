// Which request PDUs a pass-through device lets leave for a line, and what each needs
// (gateway/forward_access.h): whole requests of known length only, their counts agreeing, FC 08
// with one word, no request hidden in the frame they make; with the reason for each refusal.
#include "gateway/forward_access.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <tuple>

#include "gateway/device.h"
#include "rtu_frames.h"

namespace drivegate {
namespace {

using test::joined;
using test::with_crc;
using ::testing::HasSubstr;

constexpr std::uint8_t kSlave = 9;

// A write a slave at 1 would run: holding 0x2000 := 0x001E.
const Bytes kRun = with_crc({0x01, 0x06, 0x20, 0x00, 0x00, 0x1E});

TEST(ForwardAccess, WholeRequestsOfKnownLengthGoAndNeedWhatTheirFunctionDoes) {
  const std::vector<std::pair<Bytes, AccessLevel>> ok = {
      {{0x03, 0x00, 0x6B, 0x00, 0x03}, AccessLevel::read},      // 6.3
      {{0x04, 0x00, 0x08, 0x00, 0x01}, AccessLevel::read},      // 6.4
      {{0x07}, AccessLevel::read},                              // 6.7
      {{0x08, 0x00, 0x00, 0xA5, 0x37}, AccessLevel::read},      // 6.8: return query data
      {{0x08, 0x00, 0x01, 0x00, 0x00}, AccessLevel::maintain},  // restart communications
      {{0x08, 0x00, 0x04, 0x00, 0x00}, AccessLevel::maintain},  // force listen only mode
      {{0x18, 0x04, 0xDE}, AccessLevel::read},                  // 6.18
      {{0x2B, 0x0E, 0x01, 0x00}, AccessLevel::read},            // 6.21
      {{0x06, 0x00, 0x01, 0x00, 0x03}, AccessLevel::maintain},  // 6.6
      {{0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02}, AccessLevel::maintain},
      {{0x17, 0x00, 0x03, 0x00, 0x06, 0x00, 0x0E, 0x00, 0x03, 0x06, 0x00, 0xFF, 0x00, 0xFF, 0x00,
        0xFF},
       AccessLevel::maintain},
      {{0x14, 0x0E, 0x06, 0x00, 0x04, 0x00, 0x01, 0x00, 0x02, 0x06, 0x00, 0x03, 0x00, 0x09, 0x00,
        0x02},
       AccessLevel::read},
  };
  for (const auto& [pdu, needs] : ok) {
    const ForwardVerdict v = judge_forward(pdu, kSlave);
    EXPECT_EQ(v.refusal, Outcome::ok) << Device::describe_pdu(pdu) << ": " << v.why;
    EXPECT_EQ(v.needs, needs) << Device::describe_pdu(pdu);
  }
}

TEST(ForwardAccess, AnythingLongerShorterOrUnknownIsRefusedWithItsReason) {
  const std::vector<std::tuple<Bytes, Outcome, std::string>> refused = {
      // Trailing bytes after a whole FC 03: a write behind it.
      {joined({{0x03, 0x00, 0x00, 0x00, 0x01}, kRun}), Outcome::invalid_value,
       "13 bytes where its length is 5"},
      {{0x03, 0x00, 0x00, 0x00}, Outcome::invalid_value, "4 bytes where its length is 5"},
      {{0x10, 0x00, 0x01}, Outcome::invalid_value, "3 bytes, cut short"},
      // Return query data carrying two frames: held to one word.
      {joined({{0x08, 0x00, 0x00}, kRun, kRun}), Outcome::invalid_value,
       "19 bytes where its length is 5"},
      // A byte count its quantity does not give.
      {{0x10, 0x00, 0x01, 0x00, 0x01, 0x04, 0x00, 0x01, 0x00, 0x02},
       Outcome::invalid_value,
       "its counts disagree"},
      // Functions whose length the codec does not know: a user-defined one, 0x2B / 0x0D.
      {{0x41, 0x12, 0x34}, Outcome::denied, "function 0x41: its length is unknown"},
      {{0x2B, 0x0D, 0x00}, Outcome::denied, "function 0x2B: its length is unknown"},
      {{}, Outcome::invalid_value, "0 bytes: no request"},
  };
  for (const auto& [pdu, outcome, why] : refused) {
    const ForwardVerdict v = judge_forward(pdu, kSlave);
    EXPECT_EQ(v.refusal, outcome) << Device::describe_pdu(pdu);
    EXPECT_THAT(v.why, HasSubstr(why)) << Device::describe_pdu(pdu);
  }
}

TEST(ForwardAccess, NoFrameALengthParsingSlaveWouldTakeMayHideInsideOne) {
  // FC 14 (read file record), whole and of reference type 6 throughout, its third sub-request
  // the run at address 1 (a slave skipping 0x14 byte by byte finds it at byte 16).
  Bytes file = {0x14, 0x15, 0x06, 0, 0, 0, 0, 0, 0x01, 0x06, 0, 0, 0, 0, 0, 0x01};
  file.insert(file.end(), kRun.begin() + 1, kRun.end());
  ForwardVerdict v = judge_forward(file, kSlave);
  EXPECT_EQ(v.refusal, Outcome::invalid_value);
  EXPECT_THAT(v.why, HasSubstr("a whole request inside it, at byte 16"));
  // FC 08 return query data whose one word is the CRC of what comes before it: a slave that
  // delimits FC 08 by its CRC ends it there, and takes the real CRC for the next frame's start.
  const Bytes head = with_crc({kSlave, 0x08, 0x00, 0x00});
  v = judge_forward(Bytes{0x08, 0x00, 0x00, head[4], head[5]}, kSlave);
  EXPECT_EQ(v.refusal, Outcome::invalid_value);
  EXPECT_THAT(v.why, HasSubstr("a CRC holds before its end"));
  // The same words at another slave's address are no CRC there: forwarded.
  EXPECT_EQ(judge_forward(Bytes{0x08, 0x00, 0x00, head[4], head[5]}, kSlave + 1).refusal,
            Outcome::ok);
}

// A drive of the library's own profiles takes the user-defined 0x41 ("write without saving") laid
// out as FC 06 (vandt-e5-h, honwin-h120: docs/profiles.md, "Writes that are not saved"). A frame
// under that code hidden in a forwarded request is a frame a slave would take: refused as the
// same frame under 0x06 is, for the lowest access too. (Found by the write_code change's review.)
TEST(ForwardAccess, AFrameUnderAUserDefinedCodeMayNotHideInsideOneEither) {
  // FC 16 of 4 registers whose 8 data bytes are the V&T run, 0x8000 := 1, under 0x06 and 0x41.
  for (const std::uint8_t code : {std::uint8_t{0x06}, std::uint8_t{0x41}}) {
    const Bytes inner = with_crc({0x01, code, 0x80, 0x00, 0x00, 0x01});
    Bytes pdu = {0x10, 0x01, 0x00, 0x00, 0x04, 0x08};
    pdu.insert(pdu.end(), inner.begin(), inner.end());
    const ForwardVerdict v = judge_forward(pdu, kSlave);
    EXPECT_EQ(v.refusal, Outcome::invalid_value) << "code " << int{code};
    EXPECT_THAT(v.why, HasSubstr("a whole request inside it")) << "code " << int{code};
  }
  // A read file record (FC 14: read access) whose reference-type bytes (6) frame the V&T
  // frequency setting 0x8001 := 0x0600 under 0x41.
  const Bytes inner = with_crc({0x01, 0x41, 0x80, 0x01, 0x06, 0x00});
  Bytes pdu = {0x14, 14, 0x06, 0x00, 0x00};
  pdu.insert(pdu.end(), inner.begin(), inner.end());
  pdu.insert(pdu.end(), {0x00, 0x00, 0x01});
  const ForwardVerdict v = judge_forward(pdu, kSlave);
  EXPECT_EQ(v.needs, AccessLevel::read);
  EXPECT_EQ(v.refusal, Outcome::invalid_value);
  EXPECT_THAT(v.why, HasSubstr("a whole request inside it"));
  // Laid out as FC 16 (0x42 on the same drives): address, quantity, byte count, data.
  const Bytes multi = with_crc({0x01, 0x42, 0x80, 0x00, 0x00, 0x01, 0x02, 0x00, 0x01});
  Bytes carrier = {0x10, 0x01, 0x00, 0x00, 0x06, 0x0C};
  carrier.insert(carrier.end(), multi.begin(), multi.end());
  carrier.insert(carrier.end(), {0x00});
  ASSERT_EQ(carrier.size(), 6u + 12u);
  EXPECT_EQ(judge_forward(carrier, kSlave).refusal, Outcome::invalid_value);
}

}  // namespace
}  // namespace drivegate
