// What `drivegate events` prints of the daemon's /api/v1/events (cli/event_lines.h): one line per
// entry, oldest first, and where --follow asks from next; anything else is refused, not guessed.
#include "event_lines.h"

#include <gtest/gtest.h>

namespace drivegate::cli {
namespace {

TEST(EventLines, OneLineEachWithTimeKindDeviceAndMessage) {
  const auto page = event_lines(
      R"j({"last_seq":9,"dropped":2,"capacity":2000,"events":[)j"
      R"j({"seq":7,"unix_ms":1700000000123,"kind":"fault_raised","device":"washer-1","unit":3,)j"
      R"j("message":"washer-1: fault over_current (native 0x21)","fields":{"fault":"over_current"}},)j"
      R"j({"seq":8,"unix_ms":1700000001000,"kind":"reload","device":"","unit":0,)j"
      R"j("message":"configuration reloaded: bus a added \u00e9","fields":{}}]})j");
  ASSERT_TRUE(page.has_value());
  EXPECT_EQ(page->last_seq, 9u);
  EXPECT_EQ(page->dropped, 2u);
  EXPECT_EQ(page->newest_seq, 8u);
  ASSERT_EQ(page->lines.size(), 2u);
  EXPECT_EQ(page->lines[0],
            "2023-11-14T22:13:20.123Z  fault_raised      washer-1  washer-1: fault over_current "
            "(native 0x21)");
  EXPECT_EQ(page->lines[1],
            "2023-11-14T22:13:21.000Z  reload            -  configuration reloaded: bus a added "
            "\xC3\xA9");
}

TEST(EventLines, NoEntriesIsAPageToo) {
  const auto page = event_lines(R"j({"last_seq":0,"dropped":0,"capacity":0,"events":[]})j");
  ASSERT_TRUE(page.has_value());
  EXPECT_TRUE(page->lines.empty());
  EXPECT_EQ(page->newest_seq, 0u);
}

TEST(EventLines, AnythingElseIsRefused) {
  for (const char* bad : {"", "{}", "[]", "not found\n", R"j({"events":[{"seq":"x"}]})j",
                          R"j({"events":[)j", R"j({"last_seq":1})j"}) {
    EXPECT_FALSE(event_lines(bad).has_value()) << bad;
  }
}

TEST(EventLines, UtcTime) {
  EXPECT_EQ(utc_time(0), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(utc_time(1'700'000'000'999), "2023-11-14T22:13:20.999Z");
}

}  // namespace
}  // namespace drivegate::cli
