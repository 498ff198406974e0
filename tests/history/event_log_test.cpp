// The event history (daemon/history/event_log.h): bounded in entries and in bytes whatever is
// recorded, the oldest dropped first and counted; queries by device, kind, time and sequence;
// a repeated command counted in its entry, unless anything else happened to the device between.
#include "history/event_log.h"

#include <gtest/gtest.h>

namespace drivegate {
namespace {

class EventLogTest : public ::testing::Test {
 protected:
  EventLog log_{5, [this] { return now_ms_; }};
  std::int64_t now_ms_ = 1'700'000'000'000;

  std::uint64_t add(EventKind kind, std::string device, std::string message = "m",
                    std::vector<std::pair<std::string, std::string>> fields = {}) {
    return log_.add(Event{.kind = kind,
                          .device = std::move(device),
                          .unit = 1,
                          .message = std::move(message),
                          .fields = std::move(fields)});
  }
};

TEST_F(EventLogTest, NumbersAndStampsEachEntry) {
  EXPECT_EQ(add(EventKind::comm_lost, "a"), 1u);
  now_ms_ += 250;
  EXPECT_EQ(add(EventKind::comm_restored, "a"), 2u);
  const auto all = log_.query({});
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].seq, 1u);
  EXPECT_EQ(all[0].unix_ms, 1'700'000'000'000);
  EXPECT_EQ(all[1].unix_ms, 1'700'000'000'250);
  EXPECT_EQ(log_.last_seq(), 2u);
}

TEST_F(EventLogTest, DropsTheOldestPastItsCapacityAndCountsThem) {
  for (int i = 0; i < 12; ++i) add(EventKind::fault_raised, "a", "fault " + std::to_string(i));
  EXPECT_EQ(log_.size(), 5u);
  EXPECT_EQ(log_.dropped(), 7u);
  const auto all = log_.query({});
  ASSERT_EQ(all.size(), 5u);
  EXPECT_EQ(all.front().message, "fault 7");
  EXPECT_EQ(all.back().message, "fault 11");
  EXPECT_EQ(all.back().seq, 12u);
}

// A flood of entries as long as a client can make them: the memory stays within the bound the
// header states, and what is kept is cut, not refused.
TEST(EventLogBound, AFloodOfHugeEntriesStaysWithinItsBound) {
  constexpr std::size_t kCapacity = 200;
  EventLog log(kCapacity, [] { return std::int64_t{0}; });
  const std::string huge(4 * kMaxText, 'x');
  for (int i = 0; i < 2'000; ++i) {
    Event e{.kind = EventKind::command, .device = huge, .message = huge};
    for (int f = 0; f < 40; ++f) e.fields.emplace_back(huge, huge);
    log.add(std::move(e));
  }
  EXPECT_EQ(log.size(), kCapacity);
  EXPECT_EQ(log.dropped(), 2'000u - kCapacity);
  // Each entry: its strings cut to kMaxText, at most kMaxFields fields, plus bookkeeping.
  const std::size_t per_entry = sizeof(Event) + (2 + 2 * kMaxFields) * (kMaxText + 1) +
                                kMaxFields * sizeof(std::pair<std::string, std::string>);
  EXPECT_LE(log.memory_bytes(), kCapacity * per_entry);
  const auto kept = log.query({.limit = 1});
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].message.size(), kMaxText);
  EXPECT_EQ(kept[0].message.substr(kMaxText - 3), "...");
  EXPECT_EQ(kept[0].fields.size(), kMaxFields);
}

TEST(EventLogBound, CutsTextAtACharacterNotInsideOne) {
  EventLog log(1, [] { return std::int64_t{0}; });
  std::string text(kMaxText - 4, 'a');
  text += "\xC3\xA9\xC3\xA9\xC3\xA9";  // "ééé" across the cut
  log.add(Event{.message = text});
  const std::string kept = log.query({})[0].message;
  ASSERT_GE(kept.size(), 3u);
  EXPECT_EQ(kept.substr(kept.size() - 3), "...");
  const std::string body = kept.substr(0, kept.size() - 3);
  // No lone lead or continuation byte at the end.
  EXPECT_NE(static_cast<unsigned char>(body.back()) & 0xC0, 0xC0);
  EXPECT_TRUE(body.size() == kMaxText - 4 || body.substr(kMaxText - 4) == "\xC3\xA9");
}

TEST_F(EventLogTest, FiltersByDeviceKindTimeAndSequence) {
  add(EventKind::fault_raised, "a");   // 1 at t0
  add(EventKind::fault_raised, "b");   // 2
  now_ms_ += 10'000;
  add(EventKind::fault_cleared, "a");  // 3 at t0 + 10 s
  add(EventKind::comm_lost, "b");      // 4
  EXPECT_EQ(log_.query({.device = "a"}).size(), 2u);
  EXPECT_EQ(log_.query({.kind = EventKind::fault_raised}).size(), 2u);
  const auto recent = log_.query({.since_ms = now_ms_});
  ASSERT_EQ(recent.size(), 2u);
  EXPECT_EQ(recent[0].seq, 3u);
  const auto after = log_.query({.after_seq = 3});
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].seq, 4u);
  // The newest `limit`, oldest first.
  const auto newest = log_.query({.limit = 2});
  ASSERT_EQ(newest.size(), 2u);
  EXPECT_EQ(newest[0].seq, 3u);
  EXPECT_EQ(newest[1].seq, 4u);
  EXPECT_TRUE(log_.query({.limit = 0}).empty());
}

TEST_F(EventLogTest, ARepeatedCommandIsCountedInItsEntry) {
  const Event cmd{.kind = EventKind::command,
                  .device = "a",
                  .unit = 1,
                  .message = "write",
                  .fields = {{"client", "10.0.0.1:5000"}, {"points", "command=run_forward"},
                             {"result", "ok"}, {"took_ms", "12"}}};
  log_.add(cmd);
  Event again = cmd;
  again.fields.back().second = "40";  // a different duration is still a repeat
  now_ms_ += 100;
  EXPECT_TRUE(log_.repeat(again));
  now_ms_ += 100;
  EXPECT_TRUE(log_.repeat(again));
  ASSERT_EQ(log_.size(), 1u);
  const Event kept = log_.query({})[0];
  EXPECT_EQ(kept.field("repeats"), "2");
  EXPECT_EQ(kept.field("last_ms"), std::to_string(now_ms_));
  // Another device's entries in between do not matter...
  add(EventKind::fault_raised, "b");
  EXPECT_TRUE(log_.repeat(again));
  // ...the device's own do: the order of what happened to it is kept.
  add(EventKind::fault_raised, "a");
  EXPECT_FALSE(log_.repeat(again));
  // Another result, client or value is not a repeat.
  log_.add(cmd);
  Event refused = cmd;
  refused.fields[2].second = "refused";
  EXPECT_FALSE(log_.repeat(refused));
}

// 128 drives written in turn: each one's command is a repeat of its own newest entry however
// many others were written since; and with nothing kept (capacity 0) a repeat is still known, so
// the journal does not get a line per scan.
TEST(EventLogRepeats, AreKnownPerDeviceWhateverTheOthersAndTheCapacity) {
  for (const std::size_t capacity : {std::size_t{2000}, std::size_t{0}}) {
    EventLog log(capacity, [] { return std::int64_t{0}; });
    const auto command = [](int d) {
      return Event{.kind = EventKind::command,
                   .device = "d" + std::to_string(d),
                   .fields = {{"points", "command=run_forward"}, {"result", "ok"}}};
    };
    for (int d = 0; d < 128; ++d) log.add(command(d));
    for (int round = 0; round < 3; ++round) {
      for (int d = 0; d < 128; ++d) EXPECT_TRUE(log.repeat(command(d))) << capacity << " " << d;
    }
    EXPECT_EQ(log.size(), capacity == 0 ? 0u : 128u);
  }
}

// A field longer than the log keeps is compared as kept.
TEST(EventLogRepeats, ALongFieldStillRepeats) {
  EventLog log(10, [] { return std::int64_t{0}; });
  const Event e{.kind = EventKind::command,
                .device = "a",
                .fields = {{"points", std::string(3 * kMaxText, '7')}, {"result", "ok"}}};
  log.add(e);
  EXPECT_TRUE(log.repeat(e));
}

}  // namespace
}  // namespace drivegate
