// The trends' rings (daemon/history/trend_store.h): the newest `samples` rows kept, oldest
// first; a device whose series changed starts afresh; memory as the header states it.
#include "history/trend_store.h"

#include <gtest/gtest.h>

#include <cmath>

namespace drivegate {
namespace {

const std::vector<TrendSeries> kDrive = {{"speed_rpm", "rpm"}, {"setpoint_rpm", "rpm"}};

TEST(Trend, KeepsTheNewestRowsOldestFirst) {
  Trend t(kDrive, 3);
  for (int i = 1; i <= 5; ++i) {
    const float v[] = {static_cast<float>(i * 100), 1500.0F};
    t.add(i * 1000, v);
  }
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t.time(0), 3000);
  EXPECT_EQ(t.time(2), 5000);
  EXPECT_EQ(t.value(0, 0), 300.0F);
  EXPECT_EQ(t.value(2, 0), 500.0F);
  EXPECT_EQ(t.value(1, 1), 1500.0F);
}

TEST(TrendStore, ADeviceWhoseSeriesChangedStartsAfresh) {
  TrendStore store(10);
  const float two[] = {1.0F, 2.0F};
  store.add("device:a", kDrive, 1000, two);
  store.add("device:a", kDrive, 2000, two);
  auto more = kDrive;
  more.push_back({"current_a", "A"});
  const float three[] = {1.0F, 2.0F, 3.0F};
  store.add("device:a", more, 3000, three);
  const Trend& t = store.trends().at("device:a");
  EXPECT_EQ(t.size(), 1u);
  EXPECT_EQ(t.series().size(), 3u);
  EXPECT_EQ(t.value(0, 2), 3.0F);
}

TEST(TrendStore, KeepsOnlyWhatIsStillThere) {
  TrendStore store(10);
  const float two[] = {1.0F, 2.0F};
  store.add("device:a", kDrive, 1000, two);
  store.add("device:b", kDrive, 1000, two);
  store.keep_only({"device:b"});
  EXPECT_EQ(store.trends().size(), 1u);
  EXPECT_EQ(store.trends().count("device:b"), 1u);
}

// The header's figure: 600 rows of a time and six floats are 19.2 KB, plus the names.
TEST(TrendStore, MemoryIsTheRingsAndTheirNames) {
  TrendStore store;
  std::vector<TrendSeries> six = kDrive;
  for (const char* n : {"current_a", "voltage_v", "temperature_c", "power_w"}) {
    six.push_back({n, "x"});
  }
  const std::vector<float> row(6, 1.0F);
  for (int i = 0; i < 5000; ++i) store.add("device:a", six, i, row);
  EXPECT_EQ(store.trends().at("device:a").size(), kTrendSamples);
  EXPECT_GE(store.memory_bytes(), 600u * (8 + 6 * 4));
  EXPECT_LE(store.memory_bytes(), 600u * (8 + 6 * 4) + 2048);
}

}  // namespace
}  // namespace drivegate
