#include "base/log_context.h"

#include <vector>

namespace drivegate {

std::shared_ptr<spdlog::logger> context_logger(const spdlog::logger& base,
                                               const LogContext& context) {
  std::vector<spdlog::sink_ptr> sinks;
  for (const auto& sink : base.sinks()) {
    const auto* aware = dynamic_cast<const ContextSink*>(sink.get());
    sinks.push_back(aware != nullptr ? aware->for_context(context) : sink);
  }
  auto log = std::make_shared<spdlog::logger>(base.name(), sinks.begin(), sinks.end());
  log->set_level(base.level());
  log->flush_on(base.flush_level());
  return log;
}

}  // namespace drivegate
