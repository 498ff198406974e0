// The history's documents (daemon/history/history_json.h): /api/v1/events and /api/v1/trends as
// a client reads them.
#include "history/history_json.h"

#include <gtest/gtest.h>

#include <limits>

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
