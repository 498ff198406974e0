// The store-and-forward queue on disk (daemon/mqtt/spool.h) and its records
// (daemon/mqtt/store_forward.h), on a real directory: order, limits, restarts, damage.
#include "mqtt/spool.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "mqtt/store_forward.h"
#include "temp_dir.h"

namespace drivegate::mqtt {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class SpoolTest : public ::testing::Test {
 protected:
  // Everything waiting, in order, taken.
  static std::vector<std::string> drain(Spool& s, std::uint64_t now_ms = 0) {
    std::vector<std::string> out;
    std::error_code ec;
    while (auto r = s.front(now_ms, ec)) {
      out.push_back(r->bytes);
      s.pop();
    }
    EXPECT_FALSE(ec) << ec.message();
    return out;
  }
  std::size_t segments() const {
    std::size_t n = 0;
    for (const auto& e : fs::directory_iterator(dir_)) n += e.path().extension() == ".seg";
    return n;
  }
  test::TempDir tmp_;
  const fs::path dir_ = tmp_ / "spool";  // made by Spool::open()
};

TEST(Crc32, TheCheckValueOfIeee8023) {
  EXPECT_EQ(crc32_ieee("123456789"), 0xCBF43926U);  // the catalogue's check value
  EXPECT_EQ(crc32_ieee(""), 0U);
  EXPECT_EQ(crc32_ieee("6789", crc32_ieee("12345")), 0xCBF43926U) << "continued";
}

TEST_F(SpoolTest, OldestFirstAcrossSegmentsAndTakenSegmentsGo) {
  Spool s(dir_, {1 << 20, 24h, 64});  // 64-byte segments: a few records each
  ASSERT_FALSE(s.open());
  for (int i = 0; i < 20; ++i) ASSERT_FALSE(s.append(1000 + i, "record-" + std::to_string(i)));
  EXPECT_EQ(s.stats().records, 20u);
  EXPECT_EQ(s.stats().oldest_ms, 1000u);
  EXPECT_GT(segments(), 5u);
  std::error_code ec;
  auto r = s.front(0, ec);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->bytes, "record-0");
  EXPECT_EQ(r->stored_ms, 1000u);
  EXPECT_EQ(s.front(0, ec)->bytes, "record-0") << "front() without pop() is the same record";
  const auto all = drain(s);
  ASSERT_EQ(all.size(), 20u);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(all[i], "record-" + std::to_string(i));
  EXPECT_TRUE(s.empty());
  EXPECT_EQ(s.stats().taken, 20u);
  EXPECT_EQ(s.stats().bytes, 0u);
  EXPECT_EQ(segments(), 1u) << "only the segment being written is left";
}

TEST_F(SpoolTest, BeyondMaxBytesTheOldestGoFirstAndAreCounted) {
  Spool s(dir_, {400, 24h, 100});
  ASSERT_FALSE(s.open());
  for (int i = 0; i < 100; ++i) ASSERT_FALSE(s.append(i, "0123456789abcdef" + std::to_string(i)));
  EXPECT_LE(s.stats().bytes, 400u);
  EXPECT_GT(s.stats().dropped_size, 0u);
  EXPECT_EQ(s.stats().records + s.stats().dropped_size, 100u) << "every record accounted for";
  const auto left = drain(s);
  ASSERT_FALSE(left.empty());
  EXPECT_EQ(left.back(), "0123456789abcdef99") << "the newest kept";
  EXPECT_EQ(left.size() + s.stats().dropped_size, 100u);
}

TEST_F(SpoolTest, OlderThanMaxAgeIsDroppedWhenItsTurnComes) {
  Spool s(dir_, {1 << 20, 10s, 0});
  ASSERT_FALSE(s.open());
  ASSERT_FALSE(s.append(1'000, "old"));
  ASSERT_FALSE(s.append(50'000, "new"));
  EXPECT_EQ(drain(s, 55'000), std::vector<std::string>{"new"});
  EXPECT_EQ(s.stats().dropped_age, 1u);
  EXPECT_EQ(s.stats().taken, 1u);
}

// Reading runs ahead of the cursor: a record taken stays kept (counted, on disk, and after a
// restart) until it is released; a rewind reads what was not released again.
TEST_F(SpoolTest, TakenRecordsStayUntilReleasedAndARewindReadsThemAgain) {
  Spool s(dir_, {1 << 20, 24h, 64});
  ASSERT_FALSE(s.open());
  for (int i = 0; i < 10; ++i) ASSERT_FALSE(s.append(100 + i, "r" + std::to_string(i)));
  std::error_code ec;
  std::vector<SpoolPosition> after;
  for (int i = 0; i < 6; ++i) {
    ASSERT_EQ(s.front(0, ec)->bytes, "r" + std::to_string(i));
    s.take();
    after.push_back(s.position());
  }
  EXPECT_EQ(s.stats().records, 10u);
  EXPECT_EQ(s.taken_unreleased(), 6u);
  EXPECT_EQ(s.stats().oldest_ms, 100u);
  s.release(after[1]);  // r0, r1 done with
  EXPECT_EQ(s.stats().records, 8u);
  EXPECT_EQ(s.taken_unreleased(), 4u);
  EXPECT_EQ(s.stats().oldest_ms, 102u);
  s.release(after[0]);  // before the cursor: nothing
  EXPECT_EQ(s.stats().records, 8u);
  ASSERT_FALSE(s.sync());
  s.rewind();
  EXPECT_EQ(s.taken_unreleased(), 0u);
  EXPECT_EQ(s.front(0, ec)->bytes, "r2") << "read again from the cursor";
  {
    Spool again(dir_, {1 << 20, 24h, 64});  // (a second reader of the same files, for the test)
    ASSERT_FALSE(again.open());
    EXPECT_EQ(again.stats().records, 8u) << "taken, not released: kept across a restart";
  }
  EXPECT_EQ(drain(s), (std::vector<std::string>{"r2", "r3", "r4", "r5", "r6", "r7", "r8", "r9"}));
  EXPECT_TRUE(s.empty());
  EXPECT_EQ(segments(), 1u);
}

// Trimmed to max_bytes while records wait: the oldest waiting is still known.
TEST_F(SpoolTest, AfterASizeTrimTheOldestWaitingIsStillKnown) {
  Spool s(dir_, {400, 24h, 100});
  ASSERT_FALSE(s.open());
  for (int i = 0; i < 100; ++i) ASSERT_FALSE(s.append(1000 + i, "0123456789abcdef"));
  ASSERT_GT(s.stats().dropped_size, 0u);
  ASSERT_GT(s.stats().records, 0u);
  ASSERT_TRUE(s.stats().oldest_ms.has_value()) << s.stats().records << " records wait";
  EXPECT_EQ(*s.stats().oldest_ms, 1000u + s.stats().dropped_size);
}

TEST_F(SpoolTest, ARestartKeepsWhatWasNotTakenAfterTheLastSync) {
  {
    Spool s(dir_, {1 << 20, 24h, 64});
    ASSERT_FALSE(s.open());
    for (int i = 0; i < 10; ++i) ASSERT_FALSE(s.append(i, "r" + std::to_string(i)));
    std::error_code ec;
    for (int i = 0; i < 4; ++i) {
      ASSERT_TRUE(s.front(0, ec));
      s.pop();
    }
    ASSERT_FALSE(s.sync());
    // Taken after the last sync: replayed again after a restart (at least once, never lost).
    ASSERT_TRUE(s.front(0, ec));
    s.pop();
  }
  Spool again(dir_, {1 << 20, 24h, 64});
  ASSERT_FALSE(again.open());
  EXPECT_EQ(again.stats().records, 6u);
  EXPECT_EQ(again.stats().oldest_ms, 4u);
  ASSERT_FALSE(again.append(10, "r10"));  // appended after the restart: after the old ones
  EXPECT_EQ(drain(again), (std::vector<std::string>{"r4", "r5", "r6", "r7", "r8", "r9", "r10"}));
}

TEST_F(SpoolTest, ADamagedTailIsCutOffAtOpenAndTheRestKept) {
  {
    Spool s(dir_, {1 << 20, 24h, 0});
    ASSERT_FALSE(s.open());
    for (int i = 0; i < 5; ++i) ASSERT_FALSE(s.append(i, "intact-" + std::to_string(i)));
    ASSERT_FALSE(s.sync());
  }
  ASSERT_EQ(segments(), 1u);
  fs::path seg;
  for (const auto& e : fs::directory_iterator(dir_)) {
    if (e.path().extension() == ".seg") seg = e.path();
  }
  const auto size = fs::file_size(seg);
  {
    // A record cut short (a power cut mid-write): half a header and some bytes.
    std::ofstream(seg, std::ios::app | std::ios::binary) << std::string("\x20\x00\x00\x00\x01", 5);
  }
  Spool s(dir_, {1 << 20, 24h, 0});
  ASSERT_FALSE(s.open());
  EXPECT_EQ(s.stats().records, 5u);
  EXPECT_EQ(s.stats().dropped_corrupt, 5u);
  EXPECT_EQ(fs::file_size(seg), size) << "truncated back to the last whole record";
  // A flipped bit in the third record: it and what follows in that segment are cut off.
  {
    std::fstream f(seg, std::ios::in | std::ios::out | std::ios::binary);
    const auto third = 2 * (Spool::kHeader + 8) + Spool::kHeader + 3;
    f.seekp(static_cast<std::streamoff>(third));
    f.put('X');
  }
  Spool t(dir_, {1 << 20, 24h, 0});
  ASSERT_FALSE(t.open());
  EXPECT_EQ(drain(t), (std::vector<std::string>{"intact-0", "intact-1"}));
}

TEST_F(SpoolTest, ACursorThatIsNotOnARecordIsIgnoredAndEverythingReplayed) {
  {
    Spool s(dir_, {1 << 20, 24h, 0});
    ASSERT_FALSE(s.open());
    ASSERT_FALSE(s.append(1, "a"));
    ASSERT_FALSE(s.append(2, "b"));
  }
  for (const char* cursor : {"0000000000000001 3\n", "0000000000000009 0\n", "garbage", ""}) {
    std::ofstream(dir_ / "cursor") << cursor;
    Spool s(dir_, {1 << 20, 24h, 0});
    ASSERT_FALSE(s.open());
    EXPECT_EQ(s.stats().records, 2u) << cursor;
  }
  std::ofstream(dir_ / "cursor") << "0000000000000001 " << (Spool::kHeader + 1) << "\n";
  Spool s(dir_, {1 << 20, 24h, 0});
  ASSERT_FALSE(s.open());
  EXPECT_EQ(drain(s), std::vector<std::string>{"b"}) << "a cursor on a record is believed";
}

TEST_F(SpoolTest, ADirectoryThatCannotBeMadeIsAnError) {
  std::ofstream(dir_.string() + "-file") << "x";
  Spool s(dir_.string() + "-file", {1 << 20, 24h, 0});
  EXPECT_TRUE(s.open());
  fs::remove(dir_.string() + "-file");
}

TEST(StoredChange, RecordsRoundTripAndBrokenOnesAreRefused) {
  sparkplug::Payload p;
  p.timestamp = 1'700'000'000'000;
  sparkplug::Metric m;
  m.name = "speed_rpm";
  m.type = sparkplug::DataType::int16;
  m.value = sparkplug::MetricValue{std::int64_t{-5}};
  m.timestamp = 1'699'999'999'000;
  m.historical = true;
  p.metrics.push_back(m);
  const auto bytes = encode_record("washer-a", p);
  const auto back = decode_record(bytes);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->device, "washer-a");
  EXPECT_EQ(back->payload.timestamp, p.timestamp);
  ASSERT_EQ(back->payload.metrics.size(), 1u);
  EXPECT_EQ(back->payload.metrics[0].value, m.value);
  EXPECT_EQ(back->payload.metrics[0].timestamp, m.timestamp);
  EXPECT_TRUE(back->payload.metrics[0].historical);
  EXPECT_FALSE(decode_record(""));
  EXPECT_FALSE(decode_record(std::string("\x00\x00", 2))) << "no device name";
  EXPECT_FALSE(decode_record(std::string("\x09\x00washer", 8))) << "a name cut short";
  EXPECT_FALSE(
      decode_record(std::string("\x01\x00"
                                "a\xff\xff\xff",
                                6)))
      << "not protobuf";
}

}  // namespace
}  // namespace drivegate::mqtt
