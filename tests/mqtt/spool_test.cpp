// The store-and-forward queue on disk (daemon/mqtt/spool.h) and its records
// (daemon/mqtt/store_forward.h), on a real directory: order, limits, restarts, damage, and what
// the directory may hold instead of the spool's files (FIFOs, links, nothing at all).
#include "mqtt/spool.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "fifo_trap.h"
#include "mqtt/store_forward.h"
#include "temp_dir.h"

namespace drivegate::mqtt {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using ::testing::AllOf;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::UnorderedElementsAre;

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
  fs::path only_segment() const {
    fs::path seg;
    for (const auto& e : fs::directory_iterator(dir_)) {
      if (e.path().extension() == ".seg") seg = e.path();
    }
    return seg;
  }
  template <typename F>
  static std::chrono::milliseconds took(F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() -
                                                                 t0);
  }
  test::TempDir tmp_;
  const fs::path dir_ = tmp_ / "spool";  // made by Spool::open()
  std::vector<std::string> notes_;       // what the spool said (Spool::Note)
  Spool::Note note_ = [this](const std::string& n) { notes_.push_back(n); };
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

TEST_F(SpoolTest, ADamagedTailIsLeftOutAtOpenAndTheRestKept) {
  {
    Spool s(dir_, {1 << 20, 24h, 0});
    ASSERT_FALSE(s.open());
    for (int i = 0; i < 5; ++i) ASSERT_FALSE(s.append(i, "intact-" + std::to_string(i)));
    ASSERT_FALSE(s.sync());
  }
  ASSERT_EQ(segments(), 1u);
  const fs::path seg = only_segment();
  {
    // A record cut short (a power cut mid-write): half a header and some bytes.
    std::ofstream(seg, std::ios::app | std::ios::binary) << std::string("\x20\x00\x00\x00\x01", 5);
  }
  Spool s(dir_, {1 << 20, 24h, 0}, note_);
  ASSERT_FALSE(s.open());
  EXPECT_EQ(s.stats().records, 5u);
  EXPECT_EQ(s.stats().dropped_corrupt, 5u);
  EXPECT_THAT(notes_, ElementsAre(HasSubstr("its last 5 bytes are no whole record")));
  EXPECT_EQ(drain(s),
            (std::vector<std::string>{"intact-0", "intact-1", "intact-2", "intact-3", "intact-4"}));
}

// One flipped bit in a record costs that record, not the ones after it in its segment: the
// scan goes on at the next record whose header and CRC check out.
TEST_F(SpoolTest, AFlippedBitCostsItsRecordNotItsSegment) {
  constexpr int kRecords = 2000;
  const auto record = [](int i) { return "change-" + std::to_string(1000 + i); };  // 11 bytes
  constexpr std::uint64_t kSize = Spool::kHeader + 11;
  {
    Spool s(dir_, {64 << 20, 24h, 0});
    ASSERT_FALSE(s.open());
    for (int i = 0; i < kRecords; ++i) {
      ASSERT_FALSE(s.append(1'700'000'000'000 + i, record(i)));
    }
    ASSERT_FALSE(s.sync());
  }
  ASSERT_EQ(segments(), 1u);
  const fs::path seg = only_segment();
  const auto flip = [&](std::uint64_t at, char bit) {
    std::fstream f(seg, std::ios::in | std::ios::out | std::ios::binary);
    f.seekg(static_cast<std::streamoff>(at));
    char c = 0;
    f.get(c);
    f.seekp(static_cast<std::streamoff>(at));
    f.put(static_cast<char>(c ^ bit));
  };
  flip(100 * kSize + Spool::kHeader + 3, 0x04);  // record 100's bytes
  flip(500 * kSize + 1, 0x40);                   // record 500's length: 16 Ki more
  flip(900 * kSize + 4, 0x01);                   // record 900's CRC
  Spool s(dir_, {64 << 20, 24h, 0}, note_);
  ASSERT_FALSE(s.open());
  EXPECT_EQ(s.stats().records, kRecords - 3u);
  EXPECT_EQ(s.stats().dropped_corrupt, 3 * kSize);
  EXPECT_THAT(notes_, ElementsAre(AllOf(HasSubstr(seg.filename().string()),
                                        HasSubstr("81 damaged bytes in 3 places left out"),
                                        HasSubstr("the 1997 records around them kept"))));
  const auto all = drain(s);
  ASSERT_EQ(all.size(), kRecords - 3u);
  std::size_t k = 0;
  for (int i = 0; i < kRecords; ++i) {
    if (i == 100 || i == 500 || i == 900) continue;
    ASSERT_EQ(all[k++], record(i));
  }
  // A cursor on the record after the damage (as a run before wrote it) is believed.
  std::ofstream(dir_ / "cursor") << "0000000000000001 " << 101 * kSize << "\n";
  Spool again(dir_, {64 << 20, 24h, 0});
  ASSERT_FALSE(again.open());
  EXPECT_EQ(again.stats().records, kRecords - 101u - 2u);
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
  std::ofstream(tmp_ / "file") << "x";
  Spool s(tmp_ / "file" / "spool", {1 << 20, 24h, 0});
  EXPECT_TRUE(s.open());
}

// --- what the state directory may hold instead of the spool's files -------------------------

// Something that is no directory has the spool's name (a file, a link to a directory elsewhere,
// which would take the changes there): set aside, and a directory made.
TEST_F(SpoolTest, WhatHasTheDirectorysNameAndIsNoDirectoryIsSetAside) {
  fs::create_directories(tmp_ / "elsewhere");
  fs::create_directory_symlink(tmp_ / "elsewhere", dir_);
  Spool s(dir_, {1 << 20, 24h, 0}, note_);
  ASSERT_FALSE(s.open());
  ASSERT_FALSE(s.append(1, "a"));
  ASSERT_FALSE(s.sync());
  EXPECT_TRUE(fs::is_directory(fs::symlink_status(dir_)));
  EXPECT_TRUE(fs::is_empty(tmp_ / "elsewhere")) << "written through the link";
  EXPECT_TRUE(fs::is_symlink(dir_.string() + ".bad"));
  EXPECT_THAT(notes_, ElementsAre(HasSubstr("a symbolic link had the store's name")));
}

// A FIFO at the cursor's temporary name would block the sync's open, and the daemon with it.
TEST_F(SpoolTest, AFifoAtTheCursorsTemporaryNameNeitherBlocksNorStays) {
  Spool s(dir_, {1 << 20, 24h, 0});
  ASSERT_FALSE(s.open());
  for (int i = 0; i < 3; ++i) ASSERT_FALSE(s.append(i, "r" + std::to_string(i)));
  std::error_code ec;
  ASSERT_TRUE(s.front(0, ec));
  s.pop();
  std::error_code synced;
  {
    test::FifoTrap trap({dir_ / "cursor.tmp"});
    EXPECT_LT(took([&] { synced = s.sync(); }), 1s) << "blocked on the FIFO";
  }
  EXPECT_FALSE(synced) << synced.message();
  EXPECT_FALSE(fs::exists(fs::symlink_status(dir_ / "cursor.tmp")));
  Spool again(dir_, {1 << 20, 24h, 0});
  ASSERT_FALSE(again.open());
  EXPECT_EQ(drain(again), (std::vector<std::string>{"r1", "r2"})) << "the cursor was written";
}

// A FIFO (or anything) made at the name of the segment the spool starts next: set aside, and the
// change kept in a segment of its own, instead of every change refused with "File exists".
TEST_F(SpoolTest, SomethingAtTheNextSegmentsNameIsSetAside) {
  Spool s(dir_, {1 << 20, 24h, 64}, note_);
  ASSERT_FALSE(s.open());
  ASSERT_FALSE(s.append(1, "first"));
  const fs::path next = dir_ / "0000000000000002.seg";
  std::error_code ec;
  {
    test::FifoTrap trap({next});
    for (int i = 0; i < 10; ++i) {
      EXPECT_FALSE(s.append(2 + i, "next-" + std::to_string(i) + std::string(30, '.')));
    }
  }
  EXPECT_EQ(s.stats().refused, 0u);
  EXPECT_TRUE(fs::is_fifo(next.string() + ".bad"));
  EXPECT_THAT(notes_, ElementsAre(HasSubstr("0000000000000002.seg: a FIFO made while the store "
                                            "ran; set aside as 0000000000000002.seg.bad")));
  EXPECT_EQ(drain(s).size(), 11u);
}

// What has a segment's name at open and is not a regular file (a link, which would take the
// store's reads elsewhere, a FIFO, a directory) is set aside; the store is on, the other
// segments' records kept.
TEST_F(SpoolTest, ASegmentThatIsNoRegularFileIsSetAsideAndTheStoreGoesOn) {
  {
    Spool s(dir_, {1 << 20, 24h, 64});
    ASSERT_FALSE(s.open());
    for (int i = 0; i < 12; ++i) ASSERT_FALSE(s.append(i, "record-" + std::to_string(i)));
  }
  ASSERT_GE(segments(), 4u);
  const fs::path second = dir_ / "0000000000000002.seg";
  fs::rename(second, tmp_ / "moved.seg");
  fs::create_symlink(tmp_ / "moved.seg", second);
  ::mkfifo((dir_ / "0000000000000009.seg").c_str(), 0600);
  fs::create_directory(dir_ / "000000000000000a.seg");
  ::mkfifo((dir_ / "cursor").c_str(), 0600);
  Spool s(dir_, {1 << 20, 24h, 64}, note_);
  std::error_code opened;
  EXPECT_LT(took([&] { opened = s.open(); }), 1s);
  ASSERT_FALSE(opened) << opened.message();
  EXPECT_THAT(notes_, UnorderedElementsAre(
                          HasSubstr("0000000000000002.seg: a symbolic link, not a segment; set "
                                    "aside as 0000000000000002.seg.bad"),
                          HasSubstr("0000000000000009.seg: a FIFO, not a segment"),
                          HasSubstr("000000000000000a.seg: a directory, not a segment"),
                          HasSubstr("cursor: a FIFO, not a regular file; set aside")));
  const auto all = drain(s);
  EXPECT_EQ(all.front(), "record-0");
  EXPECT_EQ(all.back(), "record-11");
  EXPECT_EQ(all.size(), 12u - 2u) << "the linked segment's two left out, the others kept";
  ASSERT_FALSE(s.append(20, "after")) << "new segments after the set-aside names";
  ASSERT_FALSE(s.sync());
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir_ / "cursor")));
}

// A segment hard-linked elsewhere (a backup's snapshot) is read, and never written: its damaged
// tail stays as it was in both names.
TEST_F(SpoolTest, AHardLinkedSegmentIsReadAndNeverWritten) {
  {
    Spool s(dir_, {1 << 20, 24h, 0});
    ASSERT_FALSE(s.open());
    ASSERT_FALSE(s.append(1, "kept"));
  }
  const fs::path seg = only_segment();
  std::ofstream(seg, std::ios::app | std::ios::binary) << "garbage";
  const auto size = fs::file_size(seg);
  fs::create_hard_link(seg, tmp_ / "backup.seg");
  Spool s(dir_, {1 << 20, 24h, 0});
  ASSERT_FALSE(s.open());
  EXPECT_EQ(drain(s), std::vector<std::string>{"kept"});
  EXPECT_EQ(fs::file_size(tmp_ / "backup.seg"), size);
}

// The directory removed while the spool runs (rm -r of the state directory, and perhaps a mkdir
// after it): the next sync() makes it again and carries over what the open segments held that
// was not taken; changes kept afterwards go into the new directory, where a restart finds them.
// Only what was in the segments no longer open is lost, and counted.
TEST_F(SpoolTest, ADeletedDirectoryIsMadeAgainAndWhatWasOpenCarriedOver) {
  for (const bool made_again_by_hand : {false, true}) {
    SCOPED_TRACE(made_again_by_hand ? "rm -r; mkdir" : "rm -r");
    fs::remove_all(dir_);
    notes_.clear();
    {
      Spool s(dir_, {1 << 20, 24h, 64}, note_);
      ASSERT_FALSE(s.open());
      for (int i = 0; i < 12; ++i) ASSERT_FALSE(s.append(i, "before-" + std::to_string(i)));
      std::error_code ec;
      ASSERT_EQ(s.front(0, ec)->bytes, "before-0");  // the first segment open for reading
      s.pop();
      ASSERT_FALSE(s.sync());
      const auto segments_before = segments();
      ASSERT_GE(segments_before, 4u);
      fs::remove_all(dir_);
      if (made_again_by_hand) fs::create_directories(dir_);
      for (int i = 0; i < 5; ++i) ASSERT_FALSE(s.append(100 + i, "after-" + std::to_string(i)));
      EXPECT_FALSE(s.sync());
      EXPECT_TRUE(fs::is_directory(dir_));
      EXPECT_EQ(s.stats().refused, 0u);
      // The first segment (open for reading: two left in it) and the one being written are
      // carried over; the segments between went with the directory.
      const std::uint64_t lost = s.stats().dropped_lost;
      EXPECT_GT(lost, 0u);
      EXPECT_EQ(s.stats().records + lost, 11u + 5u) << "every record accounted for";
      EXPECT_THAT(notes_, ElementsAre(HasSubstr("the directory was deleted or moved away: made "
                                                "again")));
    }
    Spool again(dir_, {1 << 20, 24h, 64});
    ASSERT_FALSE(again.open());
    // The first segment's one not taken, the last segment's two, and what came after.
    EXPECT_EQ(drain(again),
              (std::vector<std::string>{"before-1", "before-10", "before-11", "after-0", "after-1",
                                        "after-2", "after-3", "after-4"}));
  }
}

// A record damaged after the scan (someone wrote into a segment while the daemon ran): the rest
// of that segment is lost, counted and said once, the file set aside; the queue goes on with the
// next segment instead of failing every read.
TEST_F(SpoolTest, ASegmentDamagedWhileRunningIsSetAsideAndTheQueueGoesOn) {
  Spool s(dir_, {1 << 20, 24h, 64}, note_);
  ASSERT_FALSE(s.open());
  for (int i = 0; i < 9; ++i) ASSERT_FALSE(s.append(i, "record-" + std::to_string(i)));
  {
    std::fstream f(dir_ / "0000000000000001.seg", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(Spool::kHeader + 2);
    f.put('#');
  }
  const auto all = drain(s);
  ASSERT_FALSE(all.empty());
  EXPECT_EQ(all.front(), "record-2") << "the first segment's two lost";
  EXPECT_EQ(all.back(), "record-8");
  EXPECT_EQ(s.stats().dropped_lost, 2u);
  EXPECT_THAT(notes_, ElementsAre(HasSubstr("a record damaged since it was written")));
  EXPECT_TRUE(fs::exists(dir_ / "0000000000000001.seg.bad"));
}

// Damage found while reading ahead of the cursor: the records taken before it are on their way to
// the broker, not lost. The segment is given up only once they are released, and then costs only
// what of it was not taken.
TEST_F(SpoolTest, DamageAheadOfTheCursorWaitsUntilWhatWasTakenIsReleased) {
  Spool s(dir_, {1 << 20, 24h, 64}, note_);  // two records a segment
  ASSERT_FALSE(s.open());
  for (int i = 0; i < 6; ++i) ASSERT_FALSE(s.append(i, "record-" + std::to_string(i)));
  {  // record-3, the second of segment 2
    std::fstream f(dir_ / "0000000000000002.seg", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(24 + Spool::kHeader + 2);
    f.put('#');
  }
  std::error_code ec;
  for (int i = 0; i < 3; ++i) {
    const auto r = s.front(0, ec);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->bytes, "record-" + std::to_string(i));
    s.take();
  }
  EXPECT_FALSE(s.front(0, ec)) << "nothing more until what was taken is released";
  EXPECT_FALSE(ec);
  EXPECT_EQ(s.stats().dropped_lost, 0u);
  EXPECT_EQ(s.taken_unreleased(), 3u);
  EXPECT_TRUE(notes_.empty());
  s.release(s.position());  // the broker confirmed record-0 to record-2
  const auto next = s.front(0, ec);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->bytes, "record-4");
  EXPECT_EQ(s.stats().dropped_lost, 1u) << "record-3 alone";
  EXPECT_THAT(notes_, ElementsAre(HasSubstr("1 change not yet sent in it lost")));
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
