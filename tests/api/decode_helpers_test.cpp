// What a simulator and a driver do with a codec's answer (include/drivegate/sim_rx.h,
// include/drivegate/driver.h), and where a flagged frame lies (include/drivegate/flagged.h): a
// made-up codec of 3-byte frames starting 0xAA, whose bad bytes
// are as many as it says, so that each answer and what it covers is known.
#include <gtest/gtest.h>

#include <vector>

#include "drivegate/driver.h"
#include "drivegate/flagged.h"
#include "drivegate/sim_rx.h"

namespace drivegate {
namespace {

// 0xAA x y: a frame of 3 (x, y its value); 0xBB: a frame whose checksum does not hold (3 bytes);
// anything else: one byte of noise. Fewer than 3 bytes after 0xAA / 0xBB: incomplete. `zero_bad`
// answers bad bytes as covering none (a codec that breaks its contract).
Decoded<int> decode(ByteView b, bool zero_bad = false) {
  if (b.empty()) return {};
  if (b[0] != 0xAA && b[0] != 0xBB)
    return decoded_bad<int>(zero_bad ? 0 : 1, FrameError::bad_header);
  if (b.size() < 3) return {};
  if (b[0] == 0xBB) return decoded_bad<int>(3, FrameError::bad_checksum);
  return decoded_frame<int>(3, b[1] * 256 + b[2]);
}

TEST(TakeDecoded, TakesEachAnswerAndDropsWhatItCoversUntilIncomplete) {
  Bytes rx{0x01, 0xAA, 0x12, 0x34, 0xBB, 0x00, 0x00, 0xAA, 0x56};
  std::vector<DecodeStatus> seen;
  while (const auto d = take_decoded(rx, [](ByteView b) { return decode(b); })) {
    seen.push_back(d->status);
    if (d->status == DecodeStatus::frame) {
      EXPECT_EQ(d->frame, 0x1234);
    }
  }
  EXPECT_EQ(seen,
            (std::vector<DecodeStatus>{DecodeStatus::bad, DecodeStatus::frame, DecodeStatus::bad}));
  EXPECT_EQ(rx, (Bytes{0xAA, 0x56}));  // incomplete: kept for the next bytes
  rx.push_back(0x78);
  const auto d = take_decoded(rx, [](ByteView b) { return decode(b); });
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->frame, 0x5678);
  EXPECT_TRUE(rx.empty());
  EXPECT_FALSE(take_decoded(rx, [](ByteView b) { return decode(b); }).has_value());
}

// An answer that covers no byte still drops one, so a loop over the buffer ends.
TEST(TakeDecoded, AlwaysMovesOn) {
  Bytes rx{0x01, 0x02, 0x03};
  int answers = 0;
  while (take_decoded(rx, [](ByteView b) { return decode(b, true); })) ++answers;
  EXPECT_EQ(answers, 3);
  EXPECT_TRUE(rx.empty());
}

TEST(UnlessFrame, IncompleteWaitsBadIsDamagedAFrameIsTheDrivers) {
  const auto incomplete = unless_frame(decode(Bytes{0xAA, 0x01}));
  ASSERT_TRUE(incomplete.has_value());
  EXPECT_EQ(incomplete->kind, RxKind::incomplete);
  EXPECT_EQ(incomplete->consumed, 0u);
  const auto checksum = unless_frame(decode(Bytes{0xBB, 0x00, 0x00}));
  ASSERT_TRUE(checksum.has_value());
  EXPECT_EQ(checksum->kind, RxKind::bad_checksum);
  EXPECT_EQ(checksum->consumed, 3u);
  const auto noise = unless_frame(decode(Bytes{0x01}));
  ASSERT_TRUE(noise.has_value());
  EXPECT_EQ(noise->kind, RxKind::noise);
  EXPECT_EQ(noise->consumed, 1u);
  EXPECT_FALSE(unless_frame(decode(Bytes{0xAA, 0x01, 0x02})).has_value());
}

// Start flag 7E, end flag 7F, at most 6 bytes on the wire.
TEST(FindFlagged, TheFrameBetweenTheFlagsOrWhatIsBadBeforeAndAroundThem) {
  struct Case {
    const char* name;
    Bytes rx;
    DecodeStatus status;
    std::size_t consumed;
    FrameError error;
    std::size_t end;  // of a frame: its end flag's index
  };
  const Case cases[] = {
      {"nothing", {}, DecodeStatus::incomplete, 0, FrameError::ok, 0},
      {"a frame", {0x7E, 1, 2, 0x7F, 0x7E}, DecodeStatus::frame, 4, FrameError::ok, 3},
      {"noise up to the start",
       {1, 2, 0x7F, 0x7E, 3},
       DecodeStatus::bad,
       3,
       FrameError::bad_header,
       0},
      {"noise, no start", {1, 2}, DecodeStatus::bad, 2, FrameError::bad_header, 0},
      {"open", {0x7E, 1, 2, 3, 4, 5}, DecodeStatus::incomplete, 0, FrameError::ok, 0},
      {"open too long", {0x7E, 1, 2, 3, 4, 5, 6}, DecodeStatus::bad, 1, FrameError::bad_length, 0},
      {"end then start", {0x7E, 0x7F, 1}, DecodeStatus::bad, 1, FrameError::bad_length, 0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const Decoded<std::size_t> d = find_flagged(c.rx, 0x7E, 0x7F, 6);
    EXPECT_EQ(d.status, c.status);
    EXPECT_EQ(d.consumed, c.consumed);
    if (c.status == DecodeStatus::bad) {
      EXPECT_EQ(d.error, c.error);
    }
    if (c.status == DecodeStatus::frame) {
      EXPECT_EQ(d.frame, c.end);
    }
    const Decoded<Bytes> as = not_a_frame<Bytes>(d);
    if (c.status != DecodeStatus::frame) {
      EXPECT_EQ(as.status, d.status);
      EXPECT_EQ(as.consumed, d.consumed);
      EXPECT_EQ(as.error, d.error);
    }
  }
}

TEST(CharacterTime, OfALineIsOfItsSettings) {
  constexpr LineDefaults line{4800, Parity::odd, 8, 1, true};
  static_assert(character_time(line) == character_time(4800, Parity::odd, 8, 1));
  EXPECT_EQ(character_time(line).count(), 11 * 1'000'000'000LL / 4800);
}

}  // namespace
}  // namespace drivegate
