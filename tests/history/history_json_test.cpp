// The history's documents (daemon/history/history_json.h): /api/v1/events and /api/v1/trends as
// a client reads them.
#include "history/history_json.h"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace drivegate {
namespace {

TEST(EventsJson, EachEntryWithItsFields) {
  EventLog log(10, [] { return std::int64_t{1'700'000'000'123}; });
  log.add(Event{.kind = EventKind::fault_raised,
                .device = "washer-1",
                .unit = 3,
                .message = "washer-1: fault over_current (native 0x21)",
                .fields = {{"fault", "over_current"}, {"native", "0x21"}}});
  log.add(Event{.kind = EventKind::reload, .message = "say \"hi\"\n"});
  EXPECT_EQ(events_json(log, {}),
            "{\"last_seq\":2,\"dropped\":0,\"started_ms\":1700000000123,\"capacity\":30,"
            "\"shelves\":{\"events\":{\"capacity\":10,\"size\":2,\"dropped\":0},"
            "\"commands\":{\"capacity\":10,\"size\":0,\"dropped\":0},"
            "\"refusals\":{\"capacity\":10,\"size\":0,\"dropped\":0}},\"events\":["
            "{\"seq\":1,\"unix_ms\":1700000000123,\"kind\":\"fault_raised\",\"device\":"
            "\"washer-1\",\"unit\":3,\"message\":\"washer-1: fault over_current (native 0x21)\","
            "\"fields\":{\"fault\":\"over_current\",\"native\":\"0x21\"}},"
            "{\"seq\":2,\"unix_ms\":1700000000123,\"kind\":\"reload\",\"device\":\"\",\"unit\":0,"
            "\"message\":\"say \\\"hi\\\"\\n\",\"fields\":{}}]}");
  // last_seq is the log's, whatever matched.
  EXPECT_EQ(events_json(log, {.device = "nobody"}),
            "{\"last_seq\":2,\"dropped\":0,\"started_ms\":1700000000123,\"capacity\":30,"
            "\"shelves\":{\"events\":{\"capacity\":10,\"size\":2,\"dropped\":0},"
            "\"commands\":{\"capacity\":10,\"size\":0,\"dropped\":0},"
            "\"refusals\":{\"capacity\":10,\"size\":0,\"dropped\":0}},\"events\":[]}");
}

Event command(int i) {
  return Event{.kind = EventKind::command,
               .device = "washer-" + std::to_string(i % 3),
               .unit = static_cast<std::uint8_t>(i % 3 + 1),
               .message = "write setpoint_rpm = " + std::to_string(100 + i),
               .fields = {{"points", "setpoint_rpm=" + std::to_string(100 + i)}, {"result", "ok"}}};
}

// A page made a slice at a time is the page made at once, each slice about the size asked for
// (an entry is never cut), and only the slices needed.
TEST(EventsPage, InSlicesIsThePageMadeAtOnce) {
  EventLog log(100, [] { return std::int64_t{1'700'000'000'000}; });
  for (int i = 0; i < 60; ++i) log.add(command(i));
  for (const EventFilter& filter : {EventFilter{}, EventFilter{.device = "washer-1", .limit = 7},
                                    EventFilter{.after_seq = 50, .limit = 1000}}) {
    EventsPage page(log, filter);
    std::size_t slices = 0;
    while (!page.render(512)) ASSERT_LT(++slices, 1000u);
    EXPECT_EQ(*page.json(), events_json(log, filter));
    EXPECT_LE(slices, page.json()->size() / 512 + 1);
  }
}

// The log changing while a page is made: an entry pushed out meanwhile is left out, one a
// repeat updated shows its count at the time; the header is the log's when the page began.
TEST(EventsPage, EntriesAreWrittenAsTheLogHoldsThemWhenTheirSliceComes) {
  EventLog log(10, [] { return std::int64_t{1'700'000'000'000}; });
  for (int i = 0; i < 10; ++i) log.add(command(i));
  EventsPage page(log, {.limit = 10});
  EXPECT_FALSE(page.render(1));                       // the first entry
  for (int i = 10; i < 13; ++i) log.add(command(i));  // seq 1..3 pushed out, 2 and 3 unwritten
  EXPECT_TRUE(log.repeat(command(12)));               // seq 13 (not in the page) counted
  EXPECT_TRUE(page.render(1 << 20));
  const std::string& json = *page.json();
  EXPECT_NE(json.find("\"last_seq\":10,"), std::string::npos) << json;
  EXPECT_NE(json.find("{\"seq\":1,"), std::string::npos);
  EXPECT_EQ(json.find("{\"seq\":2,"), std::string::npos);
  EXPECT_EQ(json.find("{\"seq\":3,"), std::string::npos);
  EXPECT_NE(json.find("{\"seq\":10,"), std::string::npos);
  EXPECT_EQ(json.find("{\"seq\":11,"), std::string::npos);
}

// One page per query and revision of the log: asked again before the log changes, the same page
// (made once); after an entry, or a repeat that changed one, a new one.
TEST(EventsPages, APageIsMadeOncePerChangeOfTheLog) {
  EventLog log(100, [] { return std::int64_t{1'700'000'000'000}; });
  for (int i = 0; i < 20; ++i) log.add(command(i));
  EventsPages pages(log);
  const auto first = pages.page({.limit = 1000});
  EXPECT_EQ(pages.page({.limit = 1000}), first) << "one being made is shared";
  first->render(1 << 20);
  EXPECT_EQ(pages.page({.limit = 1000}), first);
  EXPECT_NE(pages.page({.limit = 999}), first) << "another query, another page";
  EXPECT_NE(pages.page({.device = "washer-1", .limit = 1000}), first);
  EXPECT_TRUE(log.repeat(command(19)));
  const auto second = pages.page({.limit = 1000});
  EXPECT_NE(second, first) << "a repeat changed an entry";
  second->render(1 << 20);
  EXPECT_NE(second->json()->find("\"repeats\":\"1\""), std::string::npos);
  log.add(command(20));
  EXPECT_NE(pages.page({.limit = 1000}), second);
  // Beyond kPages queries, the least recently asked goes.
  const auto kept = pages.page({.limit = 1});
  for (std::size_t n = 2; n < 2 + EventsPages::kPages; ++n) pages.page({.limit = n});
  EXPECT_NE(pages.page({.limit = 1}), kept);
}

TEST(TrendsJson, SeriesTimesAndValuesWithGapsAsNull) {
  TrendStore store(10);
  const std::vector<TrendSeries> series = {{"speed_rpm", "rpm"}, {"current_a", "A"}};
  const float first[] = {1500.0F, 2.5F};
  const float lost[] = {std::numeric_limits<float>::quiet_NaN(),
                        std::numeric_limits<float>::quiet_NaN()};
  store.add("device:a", series, 1000, first);
  store.add("device:a", series, 2000, lost);
  store.add("bus:l", {{"utilisation", "%"}}, 2000, std::span<const float>(first, 1));
  EXPECT_EQ(trends_json(store, {.name = "device:a"}),
            "{\"samples\":10,\"trends\":[{\"name\":\"device:a\",\"series\":["
            "{\"name\":\"speed_rpm\",\"unit\":\"rpm\"},{\"name\":\"current_a\",\"unit\":\"A\"}],"
            "\"t\":[1000,2000],\"values\":[[1500,null],[2.5,null]]}]}");
  EXPECT_EQ(trends_json(store, {.name = "device:a", .since_ms = 1500}),
            "{\"samples\":10,\"trends\":[{\"name\":\"device:a\",\"series\":["
            "{\"name\":\"speed_rpm\",\"unit\":\"rpm\"},{\"name\":\"current_a\",\"unit\":\"A\"}],"
            "\"t\":[2000],\"values\":[[null],[null]]}]}");
  EXPECT_NE(trends_json(store, {}).find("\"bus:l\""), std::string::npos);
}

}  // namespace
}  // namespace drivegate
