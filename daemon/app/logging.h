// The daemon's logger. In a terminal: timestamped lines on stderr. Under systemd (JOURNAL_STREAM
// names our stderr): entries sent to the journal directly, with the message's priority and, for
// the loggers of one device or one bus (base/log_context.h), the fields DEVICE=, BUS= and
// UNIT= (the Modbus unit id), so `journalctl -u drivegate DEVICE=washer-1` selects one drive.
#pragma once

#include <spdlog/logger.h>

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "base/log_context.h"
#include "history/journal_writer.h"

namespace drivegate {

std::shared_ptr<spdlog::logger> make_logger(std::string_view name, spdlog::level::level_enum level);
std::optional<spdlog::level::level_enum> parse_log_level(std::string_view s);

// Where the audit trail's records go (history/journal_writer.h): journal entries with their
// structured fields (SYSLOG_IDENTIFIER= the logger's name, app/journal_socket.h) when the daemon
// runs under systemd, or always (`always_journal`: the command-line tool, whose terminal is not
// the journal); else, or when the journal does not take one (no journald, its queue full), the
// message, logged at info by `fallback`: every record reaches one or the other.
std::unique_ptr<JournalWriter> make_journal_writer(std::shared_ptr<spdlog::logger> fallback,
                                                   bool always_journal = false);

// The syslog priority (sd-daemon(3), syslog(3)) a message of `level` is logged with.
int syslog_priority(spdlog::level::level_enum level);

// The journal entry of one message (app/journal_socket.h): MESSAGE=, PRIORITY=,
// SYSLOG_IDENTIFIER= and the context's DEVICE=, BUS=, UNIT= where it has them.
std::vector<std::string> journal_fields(std::string_view message, spdlog::level::level_enum level,
                                        std::string_view identifier, const LogContext& context);

}  // namespace drivegate
