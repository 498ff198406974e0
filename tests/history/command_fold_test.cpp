// What a flood's records fold under (daemon/history/command_fold.h): a client by its address,
// whatever its port; the points written without a number's value but with a label's; and the
// tables of keys bounded, past which a client's, then its source kind's, overflow gathers the
// rest without losing count. On made-up time.
#include "history/command_fold.h"

#include <gtest/gtest.h>

#include "history/command_audit.h"

namespace drivegate {
namespace {

using namespace std::chrono_literals;

TEST(ClientAddress, IsTheClientWithoutItsPort) {
  EXPECT_EQ(client_address("192.0.2.7:50122"), "192.0.2.7");
  EXPECT_EQ(client_address("::1:502"), "::1");
  EXPECT_EQ(client_address("[2001:db8::7]:502"), "[2001:db8::7]");
  EXPECT_EQ(client_address("/dev/ttyS0"), "/dev/ttyS0");
  EXPECT_EQ(client_address("gw01 (primary host scada)"), "gw01 (primary host scada)");
  EXPECT_EQ(client_address(""), "");
}

TEST(FoldPoints, KeepsNamesAndLabelsNotNumbers) {
  EXPECT_EQ(fold_points("setpoint_rpm=1500 command=run_forward"),
            "setpoint_rpm command=run_forward");
  EXPECT_EQ(fold_points("accel_time=5.5 ratio=-1e+06"), "accel_time ratio");
  EXPECT_EQ(fold_points("holding 0..1 = 1 1500"), "holding");
  EXPECT_EQ(fold_points("coil 7 = 1"), "coil");
  EXPECT_EQ(fold_points("pdu 10 00 00 00 02 04 00 01 05 dc"), "pdu 10");
  EXPECT_EQ(fold_points("message=two words x=1"), "message=two x");
  EXPECT_EQ(fold_points(""), "");
  EXPECT_LE(fold_points(std::string(4000, 'a') + "=b").size(), kMaxText);
}

CommandRecord denied(const std::string& client, std::uint8_t unit) {
  CommandRecord r;
  r.source = Source{.kind = SourceKind::modbus, .listener = "0.0.0.0:502", .client = client};
  r.unit = unit;
  r.points = "holding 0 = 1";
  r.result = Outcome::denied;
  return r;
}

// One client writing to every unit, then 1000 clients: the keys tracked stay within the bound,
// the overflow keys sum up the rest, and every write is counted once.
TEST(CommandFold, ItsTablesAreBoundedAndTheOverflowsCountTheRest) {
  const FoldLimits limits{.keys = 16, .keys_per_client = 4};
  CommandFold fold(limits);
  const TimePoint t0 = TimePoint{} + 1h;
  std::uint64_t admitted = 0;
  for (int unit = 1; unit <= 200; ++unit) {
    for (int i = 0; i < 20; ++i) {
      admitted += fold.admit(
          denied("192.0.2.7:" + std::to_string(i), static_cast<std::uint8_t>(unit)), t0, 0);
    }
  }
  EXPECT_LE(fold.keys(), limits.keys_per_client + 1);  // its own four and its overflow
  for (int c = 0; c < 1000; ++c) {
    admitted += fold.admit(
        denied("198.51.100." + std::to_string(c % 250) + ":" + std::to_string(c), 1), t0, 0);
  }
  EXPECT_LE(fold.keys(), limits.keys + 1);  // and the source kind's overflow
  std::uint64_t folded = 0;
  bool client_spread = false;
  bool source_spread = false;
  for (const FoldSummary& s : fold.due(t0 + 10s)) {
    folded += s.folded;
    client_spread |= s.spread == FoldSpread::client && s.client == "192.0.2.7";
    source_spread |= s.spread == FoldSpread::source && s.client.empty();
  }
  EXPECT_TRUE(client_spread);
  EXPECT_TRUE(source_spread);
  EXPECT_EQ(admitted + folded, 200u * 20 + 1000);
  EXPECT_LE(admitted, limits.overall_burst);
}

// A key whose writes keep coming past its allowance is one summary an interval, and writes one
// by one again only once it has been quiet long enough to refill.
TEST(CommandFold, ABusyKeyFoldsOnAndAQuietOneIsForgotten) {
  CommandFold fold;
  const TimePoint t0 = TimePoint{} + 1h;
  int admitted = 0;
  int summaries = 0;
  for (int ms = 0; ms < 60'000; ms += 100) {  // 10 a second for a minute
    admitted += fold.admit(denied("192.0.2.7:1", 1), t0 + std::chrono::milliseconds(ms), ms);
    summaries += static_cast<int>(fold.due(t0 + std::chrono::milliseconds(ms)).size());
  }
  // The burst, and the one more a second brings before the key folds at 1.1 s.
  EXPECT_EQ(admitted, 11);
  EXPECT_EQ(summaries, 5);  // at 11.1, 21.2, 31.3, 41.4 and 51.5 s; the sixth is not due yet
  EXPECT_EQ(fold.due(t0 + 120s, /*all=*/true).size(), 1u);
  // Quiet long enough for its allowance to refill: forgotten, and writing one by one again.
  EXPECT_TRUE(fold.due(t0 + 140s).empty());
  EXPECT_EQ(fold.keys(), 0u);
  EXPECT_TRUE(fold.admit(denied("192.0.2.7:1", 1), t0 + 141s, 0));
}

}  // namespace
}  // namespace drivegate
