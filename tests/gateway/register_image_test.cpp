// The register image on its own (gateway/register_image.h): the adapter's points encoded from
// the driver's values, the common rows from a snapshot, ranges refused where the map has a gap,
// 32-bit values in either word order.
#include "gateway/register_image.h"

#include <gtest/gtest.h>

#include <vector>

namespace drivegate {
namespace {

class RegisterImageTest : public ::testing::Test {
 protected:
  std::vector<std::uint16_t> read(Table t, std::uint16_t address, std::size_t n,
                                  WordOrder order = WordOrder::big) {
    std::vector<std::uint16_t> out(n);
    EXPECT_TRUE(image_.covers(t, address, n));
    image_.copy(t, address, out, order);
    return out;
  }

  RegisterMap map_{{PointSpec{.name = "u", .table = Table::input, .type = PointType::u32},
                    PointSpec{.name = "w", .table = Table::input, .type = PointType::u16},
                    PointSpec{.name = "d", .table = Table::discrete}}};
  RegisterImage image_{map_};
};

TEST_F(RegisterImageTest, AdapterPointsComeFromTheDriversValues) {
  EXPECT_TRUE(image_.is_stale());
  image_.refresh_points(
      std::vector<Value>{std::int64_t{0x12345678}, std::int64_t{7}, std::int64_t{1}});
  EXPECT_FALSE(image_.is_stale());
  EXPECT_EQ(read(Table::input, kAdapterInputBase, 3),
            (std::vector<std::uint16_t>{0x1234, 0x5678, 7}));
  EXPECT_EQ(read(Table::discrete, kAdapterDiscreteBase, 1), (std::vector<std::uint16_t>{1}));
  // Little-endian: each register of the 32-bit value shows its partner's word, even half a value.
  EXPECT_EQ(read(Table::input, kAdapterInputBase, 3, WordOrder::little),
            (std::vector<std::uint16_t>{0x5678, 0x1234, 7}));
  EXPECT_EQ(read(Table::input, kAdapterInputBase + 1, 1, WordOrder::little),
            (std::vector<std::uint16_t>{0x1234}));
  image_.stale();
  EXPECT_TRUE(image_.is_stale());
  // A value the driver does not have yet reads 0.
  image_.refresh_points({});
  EXPECT_EQ(read(Table::input, kAdapterInputBase, 3), (std::vector<std::uint16_t>{0, 0, 0}));
}

TEST_F(RegisterImageTest, CommonRowsComeFromTheSnapshot) {
  const CommonState drive{.speed_rpm = -800};
  const DeviceCounters device{};
  const BusCounters bus{};
  const CommonSnapshot snapshot{.status = 0b101,
                                .faults = {},
                                .fault_code = Fault::none,
                                .drive = drive,
                                .device = device,
                                .bus = bus,
                                .data_age_ms = 250,
                                .heartbeat = 9};
  image_.refresh_common(Table::input, snapshot);
  const auto r = read(Table::input, 0, 9);
  EXPECT_EQ(r[0], 0b101);
  EXPECT_EQ(r[6], static_cast<std::uint16_t>(-800));
  EXPECT_EQ((std::uint32_t{r[7]} << 16) | r[8], 250u);
  // Only the table asked for: the holding rows and the status bits are not refreshed.
  EXPECT_EQ(read(Table::holding, 2, 1), (std::vector<std::uint16_t>{0}));
  EXPECT_EQ(read(Table::discrete, 0, 1), (std::vector<std::uint16_t>{0}));
  image_.refresh_common(Table::holding, snapshot);
  EXPECT_EQ(read(Table::holding, 2, 1), (std::vector<std::uint16_t>{9}));  // the heartbeat
  image_.refresh_common(Table::discrete, snapshot);
  EXPECT_EQ(read(Table::discrete, 0, 3), (std::vector<std::uint16_t>{1, 0, 1}));
}

TEST_F(RegisterImageTest, ARangeWithAGapOrPastTheEndIsNotCovered) {
  EXPECT_TRUE(image_.covers(Table::input, kAdapterInputBase, 3));
  EXPECT_FALSE(image_.covers(Table::input, kAdapterInputBase, 4));      // past the end
  EXPECT_FALSE(image_.covers(Table::input, kAdapterInputBase - 1, 1));  // the reserved gap
  EXPECT_FALSE(image_.covers(Table::input, 0xFFFF, 2));                 // no wrap
  EXPECT_FALSE(image_.covers(Table::coil, 0, 1));                       // an empty table
}

TEST(RegisterImage, SixtyFourBitValuesMirrorTheirFourWordsForLittleEndianClients) {
  RegisterMap map{{PointSpec{.name = "q", .table = Table::input, .type = PointType::u64},
                   PointSpec{.name = "w", .table = Table::input, .type = PointType::u16}}};
  RegisterImage image{map};
  image.refresh_points(std::vector<Value>{std::int64_t{0x1122334455667788}, std::int64_t{7}});
  std::vector<std::uint16_t> out(5);
  image.copy(Table::input, kAdapterInputBase, out, WordOrder::big);
  EXPECT_EQ(out, (std::vector<std::uint16_t>{0x1122, 0x3344, 0x5566, 0x7788, 7}));
  image.copy(Table::input, kAdapterInputBase, out, WordOrder::little);
  EXPECT_EQ(out, (std::vector<std::uint16_t>{0x7788, 0x5566, 0x3344, 0x1122, 7}));
  // Part of the value: each register shows the word at its mirror place.
  std::vector<std::uint16_t> two(2);
  image.copy(Table::input, kAdapterInputBase + 1, two, WordOrder::little);
  EXPECT_EQ(two, (std::vector<std::uint16_t>{0x5566, 0x3344}));
}

}  // namespace
}  // namespace drivegate
