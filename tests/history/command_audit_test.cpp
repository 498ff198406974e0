// The audit trail's records (daemon/history/command_audit.h): the journal fields IEC 62443-3-3
// SR 2.8 asks for, the message, the history entry; a flood of writes, accepted or refused,
// folded per client and point into summaries without losing count, on made-up time; the
// heartbeat counted only.
#include "history/command_audit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

namespace drivegate {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::Not;

// The journal as a test sees it: every entry's message and fields.
class FakeJournal final : public JournalWriter {
 public:
  struct Entry {
    std::string message;
    std::vector<std::string> fields;
  };
  void info(std::string_view message, std::span<const std::string> fields) override {
    entries.push_back({std::string(message), {fields.begin(), fields.end()}});
  }
  std::vector<Entry> entries;
};

CommandRecord tls_run() {
  CommandRecord r;
  r.source = Source{.kind = SourceKind::modbus_tls,
                    .listener = "0.0.0.0:802",
                    .client = "192.0.2.7:50122",
                    .subject = "CN=plc-1,O=plant",
                    .role = "operator"};
  r.device = "washer-1";
  r.unit = 3;
  r.points = "setpoint_rpm=1500 command=run_forward";
  r.result = Outcome::ok;
  r.took = std::chrono::milliseconds(42);
  return r;
}

class CommandAuditTest : public ::testing::Test {
 protected:
  std::int64_t wall_ms_ = 1'000;
  EventLog history_{100, [this] { return wall_ms_; }};
  FakeJournal journal_;
  CommandAudit audit_{history_, &journal_};
  TimePoint t0_ = TimePoint{} + std::chrono::hours(1);
};

TEST_F(CommandAuditTest, ARecordGoesToTheJournalWithItsFieldsAndIntoTheHistory) {
  audit_.record(tls_run(), t0_);
  ASSERT_EQ(journal_.entries.size(), 1u);
  const auto& j = journal_.entries[0];
  EXPECT_EQ(j.message,
            "write to washer-1 (unit 3) from modbus_tls 192.0.2.7:50122 on 0.0.0.0:802, "
            "certificate \"CN=plc-1,O=plant\", role operator: setpoint_rpm=1500 "
            "command=run_forward: ok, 42 ms");
  EXPECT_EQ(j.fields, (std::vector<std::string>{
                          "EVENT=command", "DEVICE=washer-1", "UNIT=3", "SOURCE=modbus_tls",
                          "LISTENER=0.0.0.0:802", "CLIENT=192.0.2.7:50122",
                          "SUBJECT=CN=plc-1,O=plant", "ROLE=operator",
                          "POINTS=setpoint_rpm=1500 command=run_forward", "RESULT=ok",
                          "TOOK_MS=42"}));
  const auto kept = history_.query({});
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].kind, EventKind::command);
  EXPECT_EQ(kept[0].device, "washer-1");
  EXPECT_EQ(kept[0].field("client"), "192.0.2.7:50122");
  EXPECT_EQ(kept[0].field("role"), "operator");
  EXPECT_EQ(audit_.counts().at(SourceKind::modbus_tls, Outcome::ok), 1u);
}

TEST_F(CommandAuditTest, ARefusalSaysWhyAndHasNoDuration) {
  CommandRecord r = tls_run();
  r.result = Outcome::denied;
  r.why = "beyond access read";
  r.took.reset();
  audit_.record(r, t0_);
  ASSERT_EQ(journal_.entries.size(), 1u);
  EXPECT_THAT(journal_.entries[0].message, HasSubstr(": denied (beyond access read)"));
  EXPECT_THAT(journal_.entries[0].fields, Contains("RESULT=denied"));
  EXPECT_THAT(journal_.entries[0].fields, Contains("WHY=beyond access read"));
  EXPECT_THAT(journal_.entries[0].fields, Not(Contains(HasSubstr("TOOK_MS"))));
}

// The fields a journal entry has, by name ("FOLDED" -> "190"); "" if none.
std::string field(const FakeJournal::Entry& e, const std::string& name) {
  for (const auto& f : e.fields) {
    if (f.starts_with(name + "=")) return f.substr(name.size() + 1);
  }
  return "";
}

// Every write a journal's entries stand for: one each, or as many as a summary says it folded.
std::uint64_t written(const std::vector<FakeJournal::Entry>& entries) {
  std::uint64_t n = 0;
  for (const auto& e : entries) {
    const std::string folded = field(e, "FOLDED");
    n += folded.empty() ? 1 : std::stoull(folded);
  }
  return n;
}

CommandRecord plain_write(std::string client, std::string points, Outcome result = Outcome::ok) {
  CommandRecord r;
  r.source =
      Source{.kind = SourceKind::modbus, .listener = "0.0.0.0:502", .client = std::move(client)};
  r.device = "washer-1";
  r.unit = 3;
  r.points = std::move(points);
  r.result = result;
  if (result == Outcome::denied) r.why = "beyond access read";
  return r;
}

// A read-only client opening a new connection for every write (a new port each time) and a PLC
// writing a new setpoint 20 times a second: each is one client writing one point, recorded one
// by one for a burst, then folded; one summary an interval says how many, when, and the last.
// Nothing is lost: every write is in a record or counted in a summary, and in the counts.
TEST_F(CommandAuditTest, AFloodFromOneClientIsFoldedIntoOneSummaryAnInterval) {
  const auto at = [&](int ms) {
    wall_ms_ = 1'000 + ms;
    return t0_ + std::chrono::milliseconds(ms);
  };
  for (int i = 0; i < 400; ++i) {  // 20 s at 20 a second, each on a connection of its own
    CommandRecord denied = plain_write("192.0.2.66:" + std::to_string(40000 + i),
                                       "holding 0 = " + std::to_string(i), Outcome::denied);
    audit_.record(denied, at(50 * i));
    audit_.record(plain_write("192.0.2.7:50122", "setpoint_rpm=" + std::to_string(1000 + i)),
                  at(50 * i + 1));
    audit_.flush(at(50 * i + 2));
  }
  audit_.flush(at(30'000));
  // Each client: its burst of 10, then a summary at 10 s and another at 20 s.
  EXPECT_EQ(journal_.entries.size(), 2u * (10 + 2));
  EXPECT_EQ(written(journal_.entries), 800u);
  EXPECT_EQ(audit_.counts().at(SourceKind::modbus, Outcome::ok), 400u);
  EXPECT_EQ(audit_.counts().at(SourceKind::modbus, Outcome::denied), 400u);
  EXPECT_EQ(audit_.counts().folded(SourceKind::modbus, Outcome::ok), 390u);
  EXPECT_EQ(audit_.counts().folded(SourceKind::modbus, Outcome::denied), 390u);
  // The first summary of the PLC's: its client's address, what it wrote, the last value.
  const auto summary = std::find_if(
      journal_.entries.begin(), journal_.entries.end(),
      [](const auto& e) { return !field(e, "FOLDED").empty() && field(e, "RESULT") == "ok"; });
  ASSERT_NE(summary, journal_.entries.end());
  EXPECT_EQ(field(*summary, "CLIENT"), "192.0.2.7");
  EXPECT_EQ(field(*summary, "DEVICE"), "washer-1");
  EXPECT_EQ(field(*summary, "SOURCE"), "modbus");
  EXPECT_EQ(field(*summary, "LISTENER"), "0.0.0.0:502");
  // From the first write past the burst (0.501 s) to the flush at 10.502 s: 201 writes.
  EXPECT_EQ(field(*summary, "FOLDED"), "201");
  EXPECT_EQ(field(*summary, "POINTS"), "setpoint_rpm=1210");
  EXPECT_EQ(field(*summary, "SINCE_MS"), "1501");
  EXPECT_EQ(field(*summary, "LAST_MS"), "11501");
  EXPECT_EQ(field(*summary, "EVENT"), "command");
  EXPECT_EQ(summary->message,
            "201 writes to washer-1 (unit 3) from modbus 192.0.2.7 on 0.0.0.0:502 in 10.0 s, "
            "folded into this record: setpoint_rpm: ok; the last: setpoint_rpm=1210");
  // The history has the same entries as the journal.
  EXPECT_EQ(history_.size(), journal_.entries.size());
  const auto refused = history_.query({.kind = EventKind::command});
  EXPECT_EQ(std::count_if(refused.begin(), refused.end(),
                          [](const Event& e) { return e.field("result") == "denied"; }),
            12);
}

// A summary is due an interval after the first write it folds, whether or not more come; and
// the daemon says every pending one as it stops.
TEST_F(CommandAuditTest, ASummaryIsWrittenWhenItsIntervalEndsOrAtTheEnd) {
  for (int i = 0; i < 15; ++i) {
    audit_.record(plain_write("192.0.2.7:1", "setpoint_rpm=" + std::to_string(i)), t0_);
  }
  EXPECT_EQ(journal_.entries.size(), 10u);
  audit_.flush(t0_ + std::chrono::milliseconds(9'999));
  EXPECT_EQ(journal_.entries.size(), 10u);
  audit_.flush(t0_ + std::chrono::seconds(10));
  ASSERT_EQ(journal_.entries.size(), 11u);
  EXPECT_EQ(field(journal_.entries.back(), "FOLDED"), "5");
  // Quiet again: the allowance refills, and the next writes are recorded one by one.
  audit_.flush(t0_ + std::chrono::seconds(30));
  audit_.record(plain_write("192.0.2.7:1", "setpoint_rpm=99"), t0_ + std::chrono::seconds(31));
  EXPECT_EQ(journal_.entries.size(), 12u);
  EXPECT_TRUE(field(journal_.entries.back(), "FOLDED").empty());
  // The daemon stopping: everything pending, due or not.
  for (int i = 0; i < 20; ++i) {
    audit_.record(plain_write("192.0.2.8:1", "setpoint_rpm=" + std::to_string(i)),
                  t0_ + std::chrono::seconds(31));
  }
  audit_.flush(t0_ + std::chrono::seconds(31), /*all=*/true);
  EXPECT_EQ(field(journal_.entries.back(), "FOLDED"), "10");
  EXPECT_EQ(written(journal_.entries), 15u + 1 + 20);
}

// Each client and point is its own: a run command amid a PLC's setpoint flood, another client's
// write, and an operate client's writes amid a read-only client's flood of refusals from many
// addresses are all recorded one by one.
TEST_F(CommandAuditTest, AFloodFoldsOnlyItsOwnClientAndPoints) {
  for (int i = 0; i < 100; ++i) {
    audit_.record(plain_write("192.0.2.7:1", "setpoint_rpm=" + std::to_string(i)), t0_);
  }
  const std::size_t before = journal_.entries.size();
  audit_.record(plain_write("192.0.2.7:1", "setpoint_rpm=5 command=run_forward"), t0_);
  audit_.record(plain_write("192.0.2.7:1", "setpoint_rpm=5 command=stop"), t0_);
  audit_.record(plain_write("192.0.2.9:1", "setpoint_rpm=5"), t0_);
  EXPECT_EQ(journal_.entries.size(), before + 3);
  // Refusals from 5000 addresses use up the refusals' overall allowance...
  for (int i = 0; i < 5000; ++i) {
    audit_.record(plain_write("198.51.100." + std::to_string(i % 250) + ":" + std::to_string(i),
                              "holding 0 = " + std::to_string(i), Outcome::denied),
                  t0_);
  }
  EXPECT_EQ(audit_.counts().at(SourceKind::modbus, Outcome::denied), 5000u);
  // ...not the accepted writes'.
  const std::size_t after = journal_.entries.size();
  audit_.record(plain_write("192.0.2.10:1", "setpoint_rpm=7"), t0_);
  EXPECT_EQ(journal_.entries.size(), after + 1);
  audit_.flush(t0_ + std::chrono::seconds(10));
  EXPECT_EQ(written(journal_.entries), 100u + 3 + 5000 + 1);
}

// However many clients, devices and points a flood spreads over, the keys tracked stay bounded,
// the journal gets at most the overall allowance and one summary per key an interval, and every
// write is counted in a record or a summary.
TEST_F(CommandAuditTest, AFloodFromEverywhereStaysWithinTheJournalsBound) {
  const FoldLimits limits;
  constexpr int kSeconds = 60;
  constexpr int kPerSecond = 2000;
  std::uint64_t sent = 0;
  for (int s = 0; s < kSeconds; ++s) {
    for (int i = 0; i < kPerSecond; ++i) {
      const int n = s * kPerSecond + i;
      CommandRecord r = plain_write(
          "10." + std::to_string(n % 7) + "." + std::to_string(n % 251) + ".1:" + std::to_string(n),
          "holding " + std::to_string(n % 100) + " = 1",
          n % 3 == 0 ? Outcome::ok : Outcome::denied);
      r.unit = static_cast<std::uint8_t>(n % 200);
      r.device = "d" + std::to_string(n % 200);
      audit_.record(r, t0_ + std::chrono::seconds(s) + std::chrono::microseconds(400 * i));
      ++sent;
    }
    audit_.flush(t0_ + std::chrono::seconds(s + 1));
  }
  audit_.flush(t0_ + std::chrono::seconds(kSeconds + 1), /*all=*/true);
  EXPECT_EQ(written(journal_.entries), sent);
  // Two allowances (accepted, refused), each: its burst, its rate, and one summary per key an
  // interval, keys at most the bound plus the source kinds' overflows.
  const std::size_t overflows = kSourceKindNames.size() * kOutcomeNames.size();
  const std::size_t intervals = kSeconds * 1000 / limits.interval.count() + 2;
  const std::size_t bound = 2 * (limits.overall_burst + kSeconds * limits.overall_per_second +
                                 intervals * (limits.keys + overflows));
  EXPECT_LE(journal_.entries.size(), bound);
  EXPECT_LT(journal_.entries.size(), sent / 20);
  std::cerr << journal_.entries.size() << " journal entries for " << sent << " writes\n";
}

// The failsafe's refused stops are what an engineer looks for after a trip: never held back,
// however many clients were refused before.
TEST_F(CommandAuditTest, TheGatewaysOwnRefusalsAreNeverHeld) {
  CommandRecord denied = tls_run();
  denied.result = Outcome::denied;
  for (int i = 0; i < 100; ++i) {
    denied.points = "holding 0 = " + std::to_string(i);
    audit_.record(denied, t0_);
  }
  const std::size_t before = journal_.entries.size();
  CommandRecord stop;
  stop.source.kind = SourceKind::failsafe;
  stop.device = "washer-1";
  stop.result = Outcome::no_response;
  for (int i = 0; i < 30; ++i) {
    stop.points = "command=stop #" + std::to_string(i);
    audit_.record(stop, t0_);
  }
  EXPECT_EQ(journal_.entries.size(), before + 30);
  // A plain Modbus client's refusals have a bucket of their own.
  CommandRecord plain = denied;
  plain.source.kind = SourceKind::modbus;
  audit_.record(plain, t0_);
  EXPECT_EQ(journal_.entries.size(), before + 31);
}

// A stuck refused write (a PLC writing a bad value every scan) is one entry counting its
// repeats, not one entry a second.
TEST_F(CommandAuditTest, ARepeatedRefusalIsARepeatNotAFlood) {
  CommandRecord bad = tls_run();
  bad.result = Outcome::invalid_value;
  bad.took.reset();
  for (int i = 0; i < 600; ++i) audit_.record(bad, t0_ + std::chrono::milliseconds(100 * i));
  EXPECT_EQ(journal_.entries.size(), 1u);
  ASSERT_EQ(history_.size(), 1u);
  EXPECT_EQ(history_.query({})[0].field("repeats"), "599");
  EXPECT_EQ(history_.query({})[0].field("result"), "invalid_value");
}

TEST_F(CommandAuditTest, ARepeatIsOneEntryAndOneJournalLine) {
  for (int i = 0; i < 100; ++i) audit_.record(tls_run(), t0_ + std::chrono::milliseconds(50 * i));
  EXPECT_EQ(journal_.entries.size(), 1u);
  ASSERT_EQ(history_.size(), 1u);
  EXPECT_EQ(history_.query({})[0].field("repeats"), "99");
  EXPECT_EQ(audit_.counts().at(SourceKind::modbus_tls, Outcome::ok), 100u);
}

TEST_F(CommandAuditTest, TheHeartbeatIsCountedNotRecorded) {
  audit_.count(SourceKind::modbus, Outcome::ok);
  EXPECT_TRUE(journal_.entries.empty());
  EXPECT_EQ(history_.size(), 0u);
  EXPECT_EQ(audit_.counts().at(SourceKind::modbus, Outcome::ok), 1u);
}

TEST(DescribeRegisters, SaysTheTableTheRangeAndTheValues) {
  const std::uint16_t v[] = {1, 1500};
  EXPECT_EQ(describe_registers(Table::holding, 0, v), "holding 0..1 = 1 1500");
  EXPECT_EQ(describe_registers(Table::coil, 7, std::span(v, 1)), "coil 7 = 1");
}

}  // namespace
}  // namespace drivegate
