// GET /api/v1/capture in routes.h: pure, so every refusal is checked without a socket.
#include <gtest/gtest.h>

#include "http/routes.h"

namespace drivegate::http {
namespace {

class OneBus final : public Content {
 public:
  std::string status_json() override { return "{}"; }
  std::string metrics() override { return ""; }
  std::string regmap_json() override { return "[]"; }
  bool has_bus(std::string_view name) override { return name == "washer line"; }
};

constexpr RouteOptions kOn{true};

TEST(CaptureRoute, ForbiddenUnlessEnabled) {
  OneBus c;
  EXPECT_EQ(route("GET", "/api/v1/capture?bus=washer%20line", c).status, 403u);
  EXPECT_EQ(route("GET", "/api/v1/capture?bus=washer%20line", c, RouteOptions{false}).status, 403u);
}

TEST(CaptureRoute, StreamsAKnownBusForTheGivenSeconds) {
  OneBus c;
  const Response r = route("GET", "/api/v1/capture?bus=washer+line&seconds=300", c, kOn);
  EXPECT_EQ(r.status, 200u);
  EXPECT_EQ(r.content_type, "application/vnd.tcpdump.pcap");
  ASSERT_TRUE(r.capture.has_value());
  EXPECT_EQ(r.capture->bus, "washer line");
  EXPECT_EQ(r.capture->duration, std::chrono::seconds(300));
  const Response d = route("GET", "/api/v1/capture?x=1&bus=washer%20line", c, kOn);
  ASSERT_TRUE(d.capture.has_value());
  EXPECT_EQ(d.capture->duration, std::chrono::seconds(10));  // the default
}

TEST(CaptureRoute, RefusesBadRequests) {
  OneBus c;
  for (const char* t : {"/api/v1/capture", "/api/v1/capture?bus=", "/api/v1/capture?bus=%4",
                        "/api/v1/capture?bus=washer%20line&seconds=0",
                        "/api/v1/capture?bus=washer%20line&seconds=301",
                        "/api/v1/capture?bus=washer%20line&seconds=",
                        "/api/v1/capture?bus=washer%20line&seconds=-1",
                        "/api/v1/capture?bus=washer%20line&seconds=1e2",
                        "/api/v1/capture?bus=washer%20line&seconds=99999999999"}) {
    const Response r = route("GET", t, c, kOn);
    EXPECT_EQ(r.status, 400u) << t;
    EXPECT_FALSE(r.capture.has_value()) << t;
  }
  EXPECT_EQ(route("GET", "/api/v1/capture?bus=other", c, kOn).status, 404u);
  EXPECT_EQ(route("POST", "/api/v1/capture?bus=washer%20line", c, kOn).status, 405u);
  EXPECT_FALSE(route("GET", "/api/v1/status", c, kOn).capture.has_value());
}

}  // namespace
}  // namespace drivegate::http
