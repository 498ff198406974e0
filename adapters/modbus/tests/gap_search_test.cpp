// GapSearch on its own: a block refused whole, a slave that lacks some of its parts (or refuses
// now and then), and the reads the search asks until it knows which parts are refused.
#include "gap_search.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <set>
#include <utility>

namespace drivegate::modbus_device {
namespace {

// `n` u16 points on holding 0, 2, 4...: a block of 2n - 1 registers, 2n - 1 parts.
Profile spaced(std::size_t n) {
  Profile p;
  p.modbus.max_registers = 125;
  p.modbus.max_gap = 1;
  for (std::size_t i = 0; i < n; ++i) {
    ProfilePoint q;
    q.name = "p" + std::to_string(i);
    q.table = Table::holding;
    q.address = static_cast<std::uint16_t>(2 * i);
    q.type = ValueType::u16;
    p.points.push_back(q);
  }
  return p;
}

// Runs the search to its end against `refuses` (asked with each read); the reads it asked.
std::vector<Block> run(GapSearch& s, const std::function<bool(const Block&)>& refuses) {
  std::vector<Block> asked;
  for (int guard = 0; !s.done() && guard < 1000; ++guard) {
    const Block b = *s.next();
    asked.push_back(b);
    s.answered(refuses(b));
  }
  EXPECT_TRUE(s.done());
  return asked;
}

// A slave lacking the registers in `missing`.
std::function<bool(const Block&)> lacking(std::set<unsigned> missing) {
  return [missing](const Block& b) {
    for (unsigned a = b.start; a < b.start + b.count; ++a) {
      if (missing.contains(a)) return true;
    }
    return false;
  };
}

TEST(GapSearch, OneMissingRegisterAnywhereIsFoundWithinTheBound) {
  const Profile p = spaced(60);
  const Block block = plan_reads(p).at(0);
  ASSERT_EQ(block.count, 119);
  const int bound = 2 * static_cast<int>(std::ceil(std::log2(119.0))) + 1;  // 15
  int most = 0;
  for (unsigned missing = 0; missing < 119; ++missing) {
    GapSearch s(p, block);
    run(s, lacking({missing}));
    ASSERT_EQ(s.refused().size(), 1u) << missing;
    EXPECT_EQ(s.refused()[0].start, missing);
    // A point (even address) is found as the point, a gap register as a gap.
    EXPECT_EQ(s.refused()[0].point.has_value(), missing % 2 == 0);
    EXPECT_FALSE(s.glitched());
    most = std::max(most, s.asked());
  }
  EXPECT_LE(most, bound);
}

TEST(GapSearch, TwoMissingRegistersAreBothFound) {
  const Profile p = spaced(10);
  GapSearch s(p, plan_reads(p).at(0));
  run(s, lacking({3, 14}));
  ASSERT_EQ(s.refused().size(), 2u);
  EXPECT_EQ(s.refused()[0].start, 3);
  EXPECT_EQ(s.refused()[1].start, 14);
}

// A point two registers wide is one part: the search never asks half of it.
TEST(GapSearch, AWidePointIsNeverCutInTwo) {
  Profile p = spaced(3);
  p.points[1].type = ValueType::u32;  // holding 2..3
  const Block b = plan_reads(p).at(0);
  ASSERT_EQ(b.count, 5);
  GapSearch s(p, b);
  for (const Block& asked : run(s, lacking({3}))) {
    EXPECT_FALSE(asked.start == 3) << "half of holding 2..3 asked";
    EXPECT_FALSE(asked.start + asked.count == 3) << "half of holding 2..3 asked";
  }
  ASSERT_EQ(s.refused().size(), 1u);
  EXPECT_EQ(s.refused()[0].start, 2);
  EXPECT_EQ(s.refused()[0].count, 2);
}

// A slave that refuses every other request, whatever it is asked: a part is never refused twice
// in a row alone, so nothing is found refused.
TEST(GapSearch, ASlaveRefusingEveryOtherRequestLacksNothing) {
  const Profile p = spaced(60);
  for (const bool first : {false, true}) {
    GapSearch s(p, plan_reads(p).at(0));
    bool refuse = first;
    run(s, [&](const Block&) { return std::exchange(refuse, !refuse); });
    EXPECT_TRUE(s.refused().empty()) << first;
    EXPECT_TRUE(s.glitched()) << first;
    EXPECT_LE(s.asked(), 7 + 2);
  }
}

// A block of one point refused: asked once more; refused again, the point is refused.
TEST(GapSearch, APointAloneIsConfirmedOnce) {
  const Profile p = spaced(1);
  GapSearch s(p, plan_reads(p).at(0));
  EXPECT_EQ(run(s, lacking({0})).size(), 1u);
  EXPECT_EQ(s.refused().size(), 1u);
  GapSearch glitch(p, plan_reads(p).at(0));
  EXPECT_EQ(run(glitch, lacking({})).size(), 1u);
  EXPECT_TRUE(glitch.refused().empty());
  EXPECT_TRUE(glitch.glitched());
}

TEST(Planner, ABlockNeverReadsThroughASkippedRegister) {
  const Profile p = spaced(4);  // holding 0, 2, 4, 6
  EXPECT_EQ(plan_reads(p).size(), 1u);
  const std::vector<std::size_t> all = {0, 1, 2, 3};
  const auto blocks = plan_reads(p, all, Skipped{{Table::holding, 3}});
  ASSERT_EQ(blocks.size(), 2u);
  EXPECT_EQ(blocks[0].start, 0);
  EXPECT_EQ(blocks[0].count, 3);
  EXPECT_EQ(blocks[1].start, 4);
  EXPECT_EQ(blocks[1].count, 3);
  // Another table's skipped register changes nothing.
  EXPECT_EQ(plan_reads(p, all, Skipped{{Table::input, 3}}).size(), 1u);
}

}  // namespace
}  // namespace drivegate::modbus_device
