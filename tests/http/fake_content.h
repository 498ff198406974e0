// A Content with fixed documents that counts what it was asked for.
#pragma once

#include <atomic>
#include <string>
#include <string_view>

#include "http/content.h"

namespace drivegate::http::test {

class FakeContent : public Content {
 public:
  std::string status_json() override {
    ++status_calls;
    return status.empty() ? R"({"devices":[]})" : status;
  }
  std::string metrics() override {
    ++metrics_calls;
    return "# HELP fake_metric a fake\n# TYPE fake_metric gauge\nfake_metric 1\n";
  }
  std::string regmap_json() override {
    ++regmap_calls;
    return R"({"regmap":true})";
  }
  // One bus, "line" (for /api/v1/capture's routing; no capture is started here).
  bool has_bus(std::string_view name) override { return name == "line"; }
  [[nodiscard]] int calls() const { return status_calls + metrics_calls + regmap_calls; }
  std::string status;  // the status document when set (before the server starts)
  std::atomic<int> status_calls{0};
  std::atomic<int> metrics_calls{0};
  std::atomic<int> regmap_calls{0};
};

}  // namespace drivegate::http::test
