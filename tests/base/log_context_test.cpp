// Per-device and per-bus loggers: the context travels as data to the sinks that record it,
// whatever the message says.
#include "base/log_context.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/base_sink.h>

#include <mutex>

namespace drivegate {
namespace {

// Records every message with the context of the logger that sent it.
class RecordingSink final : public spdlog::sinks::base_sink<std::mutex>, public ContextSink {
 public:
  struct Entry {
    std::string text;
    LogContext context;
  };
  explicit RecordingSink(std::shared_ptr<std::vector<Entry>> log, LogContext context = {})
      : log_(std::move(log)), context_(std::move(context)) {}
  spdlog::sink_ptr for_context(const LogContext& context) const override {
    return std::make_shared<RecordingSink>(log_, context);
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    log_->push_back({std::string(msg.payload.data(), msg.payload.size()), context_});
  }
  void flush_() override {}

 private:
  std::shared_ptr<std::vector<Entry>> log_;
  LogContext context_;
};

TEST(LogContext, EachLoggerCarriesItsOwnContextToTheSinks) {
  auto entries = std::make_shared<std::vector<RecordingSink::Entry>>();
  spdlog::logger root("drivegated", std::make_shared<RecordingSink>(entries));
  root.set_level(spdlog::level::debug);
  const auto washer = context_logger(root, {.device = "washer-1", .bus = "line", .unit = 3});
  const auto line = context_logger(root, {.device = "", .bus = "line", .unit = std::nullopt});
  // The text says nothing of the device: the fields do not come from it.
  washer->warn("stall");
  line->info("device washer-2: reopened");
  root.info("started");
  ASSERT_EQ(entries->size(), 3u);
  EXPECT_EQ((*entries)[0].context.device, "washer-1");
  EXPECT_EQ((*entries)[0].context.unit, 3);
  EXPECT_EQ((*entries)[1].context.device, "");  // not parsed out of the text
  EXPECT_EQ((*entries)[1].context.bus, "line");
  EXPECT_EQ((*entries)[2].context.bus, "");
  EXPECT_EQ(washer->name(), "drivegated");
  EXPECT_EQ(washer->level(), spdlog::level::debug);
}

}  // namespace
}  // namespace drivegate
