// The event history (daemon/history/event_log.h): bounded in entries and in bytes whatever is
// recorded, the oldest dropped first and counted, each shelf on its own (no flood of commands
// pushes the plant's events out, no flood of refusals the commands); queries by device, kind,
// time and sequence across the shelves; a repeated command counted in its entry, unless anything
// else happened to the device between.
#include "history/event_log.h"

#include <gtest/gtest.h>

#include <algorithm>

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

Event command(std::string source, std::string result, int n) {
  return Event{.kind = EventKind::command,
               .device = "a",
               .message = "write " + std::to_string(n),
               .fields = {{"source", std::move(source)},
                          {"points", "setpoint_rpm=" + std::to_string(n)},
                          {"result", std::move(result)}}};
}

// A comm_lost, then commands carried out and refused by the thousand: the comm_lost is still
// there, and so are the newest commands carried out, whatever the refusals; the failsafe's own
// write is kept with the plant's events.
TEST(EventLogShelves, NoFloodOfCommandsPushesThePlantsEventsOut) {
  EventLog log(HistoryBounds{.events = 10, .commands = 100, .refusals = 50},
               [] { return std::int64_t{0}; });
  log.add(Event{.kind = EventKind::comm_lost, .device = "a", .message = "a: comm lost"});
  log.add(command("failsafe", "ok", -1));
  for (int i = 0; i < 5'000; ++i) log.add(command("modbus", "ok", i));
  for (int i = 0; i < 5'000; ++i) log.add(command("modbus", "denied", i));
  EXPECT_EQ(log.query({.kind = EventKind::comm_lost}).size(), 1u);
  EXPECT_EQ(log.size(Shelf::events), 2u);
  EXPECT_EQ(log.size(Shelf::commands), 100u);
  EXPECT_EQ(log.size(Shelf::refusals), 50u);
  EXPECT_EQ(log.dropped(Shelf::events), 0u);
  EXPECT_EQ(log.dropped(Shelf::commands), 4'900u);
  EXPECT_EQ(log.dropped(Shelf::refusals), 4'950u);
  EXPECT_EQ(log.dropped(), 9'850u);
  EXPECT_EQ(log.size(), 152u);
  EXPECT_EQ(log.capacity(), 160u);
  const auto ok = log.query({.kind = EventKind::command, .limit = 1000});
  EXPECT_EQ(
      std::count_if(ok.begin(), ok.end(), [](const Event& e) { return e.field("result") == "ok"; }),
      101);  // the failsafe's and the newest 100
  EXPECT_EQ(log.query({.device = "a", .limit = 1000}).front().kind, EventKind::comm_lost);
}

// The shelves read as one list in sequence: the newest `limit`, and a follower's next page.
TEST(EventLogShelves, QueriesMergeTheShelvesInSequence) {
  EventLog log(HistoryBounds{.events = 100, .commands = 100, .refusals = 100},
               [] { return std::int64_t{0}; });
  for (int i = 0; i < 30; ++i) {
    if (i % 3 == 0) log.add(Event{.kind = EventKind::fault_raised, .device = "a"});
    if (i % 3 == 1) log.add(command("modbus", "ok", i));
    if (i % 3 == 2) log.add(command("modbus", "busy", i));
  }
  const auto seqs = [](const std::vector<Event>& v) {
    std::vector<std::uint64_t> out;
    for (const auto& e : v) out.push_back(e.seq);
    return out;
  };
  EXPECT_EQ(seqs(log.query({.limit = 4})), (std::vector<std::uint64_t>{27, 28, 29, 30}));
  EXPECT_EQ(seqs(log.query({.after_seq = 10, .limit = 4})),
            (std::vector<std::uint64_t>{11, 12, 13, 14}));
  EXPECT_EQ(seqs(log.query({.kind = EventKind::fault_raised, .after_seq = 10, .limit = 2})),
            (std::vector<std::uint64_t>{13, 16}));
  EXPECT_EQ(seqs(log.query({.kind = EventKind::command, .limit = 3})),
            (std::vector<std::uint64_t>{27, 29, 30}));
  EXPECT_EQ(log.query({.limit = 1000}).size(), 30u);
}

// A repeat counts in its entry on whichever shelf; a write folded away (interrupt) ends the run.
TEST(EventLogShelves, ARepeatIsCountedOnItsShelfUntilInterrupted) {
  EventLog log(HistoryBounds{}, [] { return std::int64_t{5}; });
  log.add(Event{.kind = EventKind::fault_raised, .device = "a"});
  log.add(command("modbus", "denied", 1));
  EXPECT_TRUE(log.repeat(command("modbus", "denied", 1)));
  EXPECT_EQ(log.query({.kind = EventKind::command})[0].field("repeats"), "1");
  log.interrupt("a");
  EXPECT_FALSE(log.repeat(command("modbus", "denied", 1)));
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
