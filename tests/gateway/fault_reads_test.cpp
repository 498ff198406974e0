// What one client has read of the drives' faults (gateway/fault_reads.h): a read showing a fault
// is kept, per drive, until a read shows none; the record is bounded. What a device records in
// it, and the runs stamped with it: device_test.cpp, DeviceFaultState.
#include "gateway/fault_reads.h"

#include <gtest/gtest.h>

#include <chrono>
#include <vector>

namespace drivegate {
namespace {

using namespace std::chrono_literals;
using TimePoint = FaultReads::TimePoint;

// A client that reads, has its reply, then sends more.
void read_and_answered(FaultReads& reads, const void* drive, bool shows_fault, TimePoint at) {
  reads.served(drive, shows_fault, at);
  reads.all_sent();
  reads.received();
}

TEST(FaultReads, AReadShowingAFaultIsKeptUntilAReadShowsNone) {
  FaultReads reads;
  const int drive = 0;
  const TimePoint t0{};
  EXPECT_FALSE(reads.fault_seen(&drive));
  read_and_answered(reads, &drive, true, t0 + 1s);
  read_and_answered(reads, &drive, true, t0 + 2s);
  EXPECT_EQ(reads.fault_seen(&drive), t0 + 2s);
  read_and_answered(reads, &drive, false, t0 + 3s);
  EXPECT_FALSE(reads.fault_seen(&drive));
}

// Served is not read: the reply has to go out, and the client send more after it.
TEST(FaultReads, AReadCountsOnceItsReplyWentOutAndTheClientSentMore) {
  FaultReads reads;
  const int drive = 0;
  const TimePoint t0{};
  reads.served(&drive, true, t0 + 1s);
  reads.received();  // more from the client, in the same segment: sent before the reply
  EXPECT_FALSE(reads.fault_seen(&drive));
  reads.all_sent();
  EXPECT_FALSE(reads.fault_seen(&drive)) << "the reply is out, nothing sent after it yet";
  reads.received();
  EXPECT_EQ(reads.fault_seen(&drive), t0 + 1s);
}

// A batch of replies goes out with the reads served before it began; one served meanwhile waits
// for the next.
TEST(FaultReads, OnlyTheReadsWhoseRepliesWentOutCount) {
  FaultReads reads;
  const int a = 0;
  const int b = 0;
  const TimePoint t0{};
  reads.served(&a, true, t0 + 1s);
  const std::uint64_t batch = reads.served_count();
  reads.served(&b, true, t0 + 2s);
  reads.sent(batch);
  reads.received();
  EXPECT_EQ(reads.fault_seen(&a), t0 + 1s);
  EXPECT_FALSE(reads.fault_seen(&b));
  reads.sent(reads.served_count());
  reads.received();
  EXPECT_EQ(reads.fault_seen(&b), t0 + 2s);
}

// A serial master that sent again before the reply was due: that reply never goes out.
TEST(FaultReads, AReadWhoseReplyWasDroppedNeverCounts) {
  FaultReads reads;
  const int drive = 0;
  const TimePoint t0{};
  reads.served(&drive, true, t0 + 1s);
  reads.unsent_dropped();
  reads.received();
  reads.served(&drive, false, t0 + 2s);  // the next read's reply goes out
  reads.all_sent();
  reads.received();
  EXPECT_FALSE(reads.fault_seen(&drive));
}

TEST(FaultReads, KeepsTheNewestOfItsBoundedDrives) {
  FaultReads reads;
  std::vector<int> drives(FaultReads::kMaxDrives + 1);
  const TimePoint t0{};
  for (std::size_t i = 0; i < drives.size(); ++i) {
    read_and_answered(reads, &drives[i], true, t0 + i * 1ms);
  }
  EXPECT_FALSE(reads.fault_seen(&drives.front())) << "the oldest goes first";
  for (std::size_t i = 1; i < drives.size(); ++i) {
    EXPECT_EQ(reads.fault_seen(&drives[i]), t0 + i * 1ms);
  }
}

// A client that pipelines reads without reading its replies keeps at most kMaxInFlight of them;
// the newest count once their replies go out.
TEST(FaultReads, ReadsInFlightAreBounded) {
  FaultReads reads;
  std::vector<int> drives(FaultReads::kMaxInFlight + 10);
  const TimePoint t0{};
  for (std::size_t i = 0; i < drives.size(); ++i) reads.served(&drives[i], true, t0 + i * 1ms);
  reads.all_sent();
  reads.received();
  EXPECT_FALSE(reads.fault_seen(&drives.front()));
  EXPECT_EQ(reads.fault_seen(&drives.back()), t0 + (drives.size() - 1) * 1ms);
}

}  // namespace
}  // namespace drivegate
