// The daemon's logger. In a terminal: timestamped lines on stderr. Under systemd (JOURNAL_STREAM
// names our stderr): lines with the kernel-style "<N>" priority prefix journald understands, and
// no timestamp of our own.
#pragma once

#include <memory>
#include <optional>
#include <spdlog/logger.h>
#include <string_view>

namespace drivegate {

std::shared_ptr<spdlog::logger> make_logger(std::string_view name, spdlog::level::level_enum level);
std::optional<spdlog::level::level_enum> parse_log_level(std::string_view s);

}  // namespace drivegate
