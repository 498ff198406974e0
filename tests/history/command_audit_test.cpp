// The audit trail's records (daemon/history/command_audit.h): the journal fields IEC 62443-3-3
// SR 2.8 asks for, the message, the history entry; a flood of refusals paced per cause without
// losing count; the heartbeat counted only.
#include "history/command_audit.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

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
  EventLog history_{100, [] { return std::int64_t{1'000}; }};
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

// A client hammering refused writes: every one counted, a burst recorded, then one a second;
// the next one recorded says how many were not. The plant's events are not pushed out.
TEST_F(CommandAuditTest, AFloodOfRefusalsIsPacedPerCauseAndCounted) {
  history_.add(Event{.kind = EventKind::fault_raised, .device = "washer-1"});
  CommandRecord denied = tls_run();
  denied.result = Outcome::denied;
  denied.took.reset();
  for (int i = 0; i < 5000; ++i) {
    denied.points = "holding 0 = " + std::to_string(i);  // no two alike: no repeats
    audit_.record(denied, t0_);
  }
  EXPECT_EQ(audit_.counts().at(SourceKind::modbus_tls, Outcome::denied), 5000u);
  EXPECT_EQ(journal_.entries.size(), 10u);
  EXPECT_EQ(history_.size(), 11u);
  EXPECT_EQ(history_.query({.kind = EventKind::fault_raised}).size(), 1u);
  // Another cause has its own bucket.
  CommandRecord busy = denied;
  busy.result = Outcome::busy;
  audit_.record(busy, t0_);
  EXPECT_EQ(journal_.entries.size(), 11u);
  // A second later: recorded again, saying how many were held.
  denied.points = "holding 0 = last";
  audit_.record(denied, t0_ + std::chrono::seconds(1));
  ASSERT_EQ(journal_.entries.size(), 12u);
  EXPECT_THAT(journal_.entries.back().message,
              HasSubstr("(4990 more denied from modbus_tls clients not recorded)"));
  EXPECT_THAT(journal_.entries.back().fields, Contains("HELD=4990"));
  // Writes that succeed are never paced.
  for (int i = 0; i < 50; ++i) {
    CommandRecord ok = tls_run();
    ok.points = "setpoint_rpm=" + std::to_string(i);
    audit_.record(ok, t0_ + std::chrono::seconds(1));
  }
  EXPECT_EQ(journal_.entries.size(), 62u);
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
