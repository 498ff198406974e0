// Per-device and per-bus loggers: the daemon's sinks and level, with what their messages concern
// attached as data (the journal's DEVICE=, BUS= and UNIT= fields) rather than parsed back out of
// the text. A sink that records the context implements ContextSink (app/logging.cpp's journal
// sink); every other sink is shared as it is.
#pragma once

#include <spdlog/logger.h>
#include <spdlog/sinks/sink.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

namespace drivegate {

struct LogContext {
  std::string device;  // empty: not about one device
  std::string bus;     // empty: not about one bus
  std::optional<std::uint8_t> unit;
};

class ContextSink {
 public:
  virtual ~ContextSink() = default;
  // A sink like this one that attaches `context` to every message.
  [[nodiscard]] virtual spdlog::sink_ptr for_context(const LogContext& context) const = 0;
};

// A logger with `base`'s name, level and sinks, its context sinks given `context`.
std::shared_ptr<spdlog::logger> context_logger(const spdlog::logger& base,
                                               const LogContext& context);

}  // namespace drivegate
