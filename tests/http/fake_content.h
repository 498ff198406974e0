// A Content with fixed documents that counts what it was asked for.
#pragma once

#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

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
  // One bus, "line", whose capture streams a pcap global header and then nothing (the line is
  // quiet) until the client leaves or its time is up.
  bool has_bus(std::string_view name) override { return name == "line"; }
  std::unique_ptr<CaptureStream> start_capture(std::string_view name, std::size_t /*max_bytes*/,
                                               std::function<void()> on_data) override {
    if (name != "line") return nullptr;
    ++captures_started;
    on_data();  // the global header is there to take
    return std::make_unique<QuietCapture>();
  }
  // The history's documents: what the route parsed is kept; only "command" is a known kind. The
  // events page is `events` (a small one unless set), made in slices of the size asked for.
  std::shared_ptr<SlicedDocument> events_page(const EventsQuery& q) override {
    ++history_calls;
    events_query = q;
    if (!q.kind.empty() && q.kind != "command") return nullptr;
    return std::make_shared<Page>(events.empty() ? R"({"events":[]})" : events, slices);
  }
  std::string trends_json(const TrendsQuery& q) override {
    ++history_calls;
    trends_query = q;
    return R"({"trends":[]})";
  }
  EventsQuery events_query;
  TrendsQuery trends_query;
  [[nodiscard]] int calls() const { return status_calls + metrics_calls + regmap_calls; }
  std::string status;          // the status document when set (before the server starts)
  std::string events;          // the events page when set (before the server starts)
  std::atomic<int> slices{0};  // of events pages rendered, all pages together
  std::atomic<int> status_calls{0};
  std::atomic<int> metrics_calls{0};
  std::atomic<int> regmap_calls{0};
  std::atomic<int> captures_started{0};
  std::atomic<int> history_calls{0};  // events_page and trends_json, refused or not

 private:
  class Page : public SlicedDocument {
   public:
    Page(std::string text, std::atomic<int>& slices) : text_(std::move(text)), slices_(slices) {}
    bool render_slice(std::size_t bytes) override {
      ++slices_;
      made_ = std::min(text_.size(), made_ + bytes);
      if (made_ == text_.size()) json_ = std::make_shared<const std::string>(text_);
      return whole();
    }
    [[nodiscard]] bool whole() const override { return json_ != nullptr; }
    [[nodiscard]] std::shared_ptr<const std::string> document() const override { return json_; }

   private:
    std::string text_;
    std::atomic<int>& slices_;
    std::size_t made_ = 0;
    std::shared_ptr<const std::string> json_;
  };
  class QuietCapture : public CaptureStream {
   public:
    std::string take() override { return std::exchange(header_, {}); }
    [[nodiscard]] bool full() const override { return false; }

   private:
    std::string header_ = std::string("\xd4\xc3\xb2\xa1", 4);  // the pcap magic, for a start
  };
};

}  // namespace drivegate::http::test
