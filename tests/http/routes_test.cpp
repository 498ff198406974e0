// The routes, pure: every document, its content type and body, HEAD, query strings, 404 and 405.
#include "http/routes.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fake_content.h"

namespace drivegate::http::test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr const char* kPrometheus = "text/plain; version=0.0.4; charset=utf-8";

class Routes : public ::testing::Test {
 protected:
  FakeContent content;
};

TEST_F(Routes, StatusPageAtRootAndIndex) {
  for (const char* target : {"/", "/index.html", "/?refresh=1"}) {
    SCOPED_TRACE(target);
    const Response r = route("GET", target, content);
    EXPECT_EQ(r.status, 200u);
    EXPECT_EQ(r.content_type, "text/html; charset=utf-8");
    EXPECT_EQ(r.body, std::string(status_page()));
    EXPECT_THAT(r.body, HasSubstr("<html"));
    EXPECT_EQ(r.allow, "");
  }
  EXPECT_EQ(content.calls(), 0);  // the page is static: it fetches the JSON itself
}

TEST_F(Routes, StatusJson) {
  const Response r = route("GET", "/api/v1/status", content);
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.content_type, "application/json");
  EXPECT_EQ(r.body, R"({"devices":[]})");
  EXPECT_EQ(content.status_calls, 1);
  EXPECT_EQ(content.calls(), 1);
}

TEST_F(Routes, RegmapJson) {
  const Response r = route("GET", "/api/v1/regmap", content);
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.content_type, "application/json");
  EXPECT_EQ(r.body, R"({"regmap":true})");
  EXPECT_EQ(content.regmap_calls, 1);
  EXPECT_EQ(content.calls(), 1);
}

TEST_F(Routes, MetricsArePrometheusText004) {
  const Response r = route("GET", "/metrics", content);
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.content_type, kPrometheus);
  EXPECT_THAT(r.body, StartsWith("# HELP fake_metric"));
  EXPECT_EQ(content.metrics_calls, 1);
  EXPECT_EQ(content.calls(), 1);
}

TEST_F(Routes, QueryStringIsIgnored) {
  EXPECT_EQ(route("GET", "/metrics?name[]=x&y", content).content_type, kPrometheus);
  EXPECT_EQ(route("GET", "/api/v1/status?", content).status, 200u);
  EXPECT_EQ(route("GET", "/api/v1/regmap?format=csv", content).content_type, "application/json");
  EXPECT_EQ(content.calls(), 3);
}

TEST_F(Routes, HeadAnswersAsGetDoes) {
  // The server strips HEAD's body; the route gives the same status, type and length as GET.
  for (const char* target : {"/", "/api/v1/status", "/api/v1/regmap", "/metrics", "/nope"}) {
    SCOPED_TRACE(target);
    const Response get = route("GET", target, content);
    const Response head = route("HEAD", target, content);
    EXPECT_EQ(head.status, get.status);
    EXPECT_EQ(head.content_type, get.content_type);
    EXPECT_EQ(head.body.size(), get.body.size());
  }
}

TEST_F(Routes, UnknownTargetsAre404) {
  for (const char* target :
       {"/nope", "/metrics/", "/metricsx", "/METRICS", "/api/v1/status/", "/api/v1", "/api/v2/status",
        "//metrics", "/index.htm", "metrics", "*", "", "/%6detrics",
        "http://127.0.0.1/metrics", "/../metrics"}) {
    SCOPED_TRACE(target);
    const Response r = route("GET", target, content);
    EXPECT_EQ(r.status, 404u);
    EXPECT_EQ(r.content_type, "text/plain; charset=utf-8");
    EXPECT_EQ(r.allow, "");
  }
  EXPECT_EQ(content.calls(), 0);
}

TEST_F(Routes, OtherMethodsAre405WithAllow) {
  for (const char* method :
       {"POST", "PUT", "DELETE", "PATCH", "OPTIONS", "TRACE", "CONNECT", "get", "head", "GETX", ""}) {
    for (const char* target : {"/", "/metrics", "/api/v1/status", "/nope"}) {
      SCOPED_TRACE(std::string(method) + " " + target);
      const Response r = route(method, target, content);
      EXPECT_EQ(r.status, 405u);
      EXPECT_EQ(r.allow, "GET, HEAD");
      EXPECT_EQ(r.content_type, "text/plain; charset=utf-8");
      EXPECT_THAT(r.body, HasSubstr("read-only"));
    }
  }
  EXPECT_EQ(content.calls(), 0);  // nothing is rendered for a refused method
}

TEST_F(Routes, CaptureIsRefusedUnlessEnabled) {
  for (const char* target : {"/api/v1/capture", "/api/v1/capture?bus=line"}) {
    SCOPED_TRACE(target);
    const Response r = route("GET", target, content);  // default RouteOptions: capture off
    EXPECT_EQ(r.status, 403u);
    EXPECT_FALSE(r.capture);
    EXPECT_EQ(r.content_type, "text/plain; charset=utf-8");
  }
}

TEST_F(Routes, CaptureNeedsAKnownBusAndSane1To300Seconds) {
  const RouteOptions on{.capture = true};
  struct Case {
    const char* target;
    unsigned status;
    long seconds;  // for 200
  };
  for (const Case& c : {Case{"/api/v1/capture", 400, 0}, Case{"/api/v1/capture?bus=", 400, 0},
                        Case{"/api/v1/capture?bus", 400, 0}, Case{"/api/v1/capture?bus=%zz", 400, 0},
                        Case{"/api/v1/capture?bus=nope", 404, 0},
                        Case{"/api/v1/capture?bus=line", 200, 10},
                        Case{"/api/v1/capture?bus=l%69ne&seconds=300", 200, 300},
                        Case{"/api/v1/capture?seconds=1&bus=line", 200, 1},
                        Case{"/api/v1/capture?bus=line&seconds=0", 400, 0},
                        Case{"/api/v1/capture?bus=line&seconds=301", 400, 0},
                        Case{"/api/v1/capture?bus=line&seconds=-5", 400, 0},
                        Case{"/api/v1/capture?bus=line&seconds=1e2", 400, 0},
                        Case{"/api/v1/capture?bus=line&seconds=99999999999999999999", 400, 0},
                        Case{"/api/v1/capture?bus=line&seconds=", 400, 0}}) {
    SCOPED_TRACE(c.target);
    const Response r = route("GET", c.target, content, on);
    EXPECT_EQ(r.status, c.status);
    EXPECT_EQ(r.capture.has_value(), c.status == 200);
    if (r.capture) {
      EXPECT_EQ(r.capture->bus, "line");
      EXPECT_EQ(r.capture->duration.count(), c.seconds);
      EXPECT_EQ(r.content_type, "application/vnd.tcpdump.pcap");
    }
  }
  EXPECT_EQ(route("POST", "/api/v1/capture?bus=line", content, on).status, 405u);
}

// /api/v1/events and /api/v1/trends: each parameter parsed as the history reads it, anything that
// is not a number in range a 400 before the daemon is asked.
TEST_F(Routes, EventsParsesItsFiltersAndRefusesNonsense) {
  auto r = route("GET", "/api/v1/events?device=washer%2D1&kind=command&since=1700000000.5&after=41"
                        "&limit=7", content);
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.content_type, "application/json");
  EXPECT_EQ(content.events_query.device, "washer-1");
  EXPECT_EQ(content.events_query.kind, "command");
  EXPECT_EQ(content.events_query.since_ms, 1'700'000'000'500);
  EXPECT_EQ(content.events_query.after, 41u);
  EXPECT_EQ(content.events_query.limit, 7u);
  for (const char* bad : {"?kind=nonsense", "?since=abc", "?since=-1", "?since=1e99",
                          "?since=99999999999999999999", "?since=", "?after=x", "?after=-3",
                          "?limit=0", "?limit=12x", "?limit=99999999999",
                          // A broken escape is not "any device" (it was, before).
                          "?device=%zz", "?device=washer%2", "?kind=%"}) {
    EXPECT_EQ(route("GET", std::string("/api/v1/events") + bad, content).status, 400u) << bad;
  }
}

TEST_F(Routes, TrendsOfADeviceOrABusNotBoth) {
  EXPECT_EQ(route("GET", "/api/v1/trends?device=a&since=5", content).status, 200u);
  EXPECT_EQ(content.trends_query.name, "device:a");
  EXPECT_EQ(content.trends_query.since_ms, 5000);
  EXPECT_EQ(route("GET", "/api/v1/trends?bus=l", content).status, 200u);
  EXPECT_EQ(content.trends_query.name, "bus:l");
  EXPECT_EQ(route("GET", "/api/v1/trends?device=a&bus=l", content).status, 400u);
  EXPECT_EQ(route("GET", "/api/v1/trends?since=x", content).status, 400u);
  EXPECT_EQ(route("GET", "/api/v1/trends?device=%zz", content).status, 400u);
}

}  // namespace
}  // namespace drivegate::http::test
