#include "app/logging.h"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <optional>
#include <string>

#include "app/journal_socket.h"

namespace drivegate {
namespace {

// systemd sets JOURNAL_STREAM to "dev:inode" of the stream it connected to our stderr
// (systemd.exec(5), "Environment variables set or propagated by the service manager").
bool stderr_is_journal() {
  const char* js = std::getenv("JOURNAL_STREAM");
  if (js == nullptr) return false;
  struct stat st {};
  if (fstat(fileno(stderr), &st) != 0) return false;
  const std::string expected = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  return expected == js;
}

// Entries with their fields, over the journal's native protocol (journal_socket.h). When
// sending fails the line goes to stderr, which is the journal's stream, with the "<N>" priority
// prefix journald reads there (sd-daemon(3)). Each device's and bus's logger has its own sink,
// made by for_context(), carrying that device's or bus's fields; they share one socket.
class JournalSink final : public spdlog::sinks::base_sink<std::mutex>, public ContextSink {
 public:
  JournalSink() : socket_(std::make_shared<JournalSocket>()) {}
  JournalSink(std::shared_ptr<const JournalSocket> socket, LogContext context)
      : socket_(std::move(socket)), context_(std::move(context)) {}

  [[nodiscard]] spdlog::sink_ptr for_context(const LogContext& context) const override {
    auto copy = std::make_shared<JournalSink>(socket_, context);
    copy->set_level(level());
    return copy;
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    const std::string_view text(msg.payload.data(), msg.payload.size());
    const std::vector<std::string> fields =
        journal_fields(text, msg.level,
                       std::string_view(msg.logger_name.data(), msg.logger_name.size()), context_);
    if (socket_->send(fields)) {
      std::fprintf(stderr, "<%d>%.*s\n", syslog_priority(msg.level), static_cast<int>(text.size()),
                   text.data());
    }
  }
  void flush_() override { std::fflush(stderr); }

 private:
  std::shared_ptr<const JournalSocket> socket_;
  const LogContext context_{};
};

// The audit trail's entries, over the journal's native protocol; when the journal does not take
// one (not there, not listening, full), the logger's line.
class NativeJournal final : public JournalWriter {
 public:
  NativeJournal(std::shared_ptr<spdlog::logger> fallback, bool native)
      : fallback_(std::move(fallback)) {
    if (native) socket_.emplace();
  }

  void info(std::string_view message, std::span<const std::string> fields) override {
    if (socket_) {
      std::vector<std::string> all;
      all.reserve(fields.size() + 3);
      all.push_back("MESSAGE=" + std::string(message));
      all.push_back("PRIORITY=" + std::to_string(syslog_priority(spdlog::level::info)));
      all.push_back("SYSLOG_IDENTIFIER=" + fallback_->name());
      all.insert(all.end(), fields.begin(), fields.end());
      if (!socket_->send(all)) return;
    }
    fallback_->info("{}", message);
  }

 private:
  std::shared_ptr<spdlog::logger> fallback_;
  std::optional<JournalSocket> socket_;  // none: not the journal's to have
};

}  // namespace

std::unique_ptr<JournalWriter> make_journal_writer(std::shared_ptr<spdlog::logger> fallback,
                                                   bool always_journal) {
  return std::make_unique<NativeJournal>(std::move(fallback),
                                         always_journal || stderr_is_journal());
}

int syslog_priority(spdlog::level::level_enum level) {
  // syslog(3): 2 LOG_CRIT, 3 LOG_ERR, 4 LOG_WARNING, 6 LOG_INFO, 7 LOG_DEBUG.
  switch (level) {
    case spdlog::level::trace:
    case spdlog::level::debug:
      return 7;
    case spdlog::level::warn:
      return 4;
    case spdlog::level::err:
      return 3;
    case spdlog::level::critical:
      return 2;
    case spdlog::level::info:
    case spdlog::level::off:
    case spdlog::level::n_levels:
      break;
  }
  return 6;
}

std::vector<std::string> journal_fields(std::string_view message, spdlog::level::level_enum level,
                                        std::string_view identifier, const LogContext& context) {
  std::vector<std::string> fields;
  fields.reserve(6);
  fields.push_back("MESSAGE=" + std::string(message));
  fields.push_back("PRIORITY=" + std::to_string(syslog_priority(level)));
  fields.push_back("SYSLOG_IDENTIFIER=" + std::string(identifier));
  if (!context.device.empty()) fields.push_back("DEVICE=" + context.device);
  if (!context.bus.empty()) fields.push_back("BUS=" + context.bus);
  if (context.unit) fields.push_back("UNIT=" + std::to_string(*context.unit));
  return fields;
}

std::shared_ptr<spdlog::logger> make_logger(std::string_view name,
                                            spdlog::level::level_enum level) {
  spdlog::sink_ptr sink;
  if (stderr_is_journal()) {
    sink = std::make_shared<JournalSink>();
  } else {
    sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
    auto formatter = std::make_unique<spdlog::pattern_formatter>();
    formatter->set_pattern("%Y-%m-%d %H:%M:%S.%e %^%-5l%$ %v");
    sink->set_formatter(std::move(formatter));
  }
  auto logger = std::make_shared<spdlog::logger>(std::string(name), std::move(sink));
  logger->set_level(level);
  logger->flush_on(spdlog::level::trace);
  return logger;
}

std::optional<spdlog::level::level_enum> parse_log_level(std::string_view s) {
  if (s == "trace") return spdlog::level::trace;
  if (s == "debug") return spdlog::level::debug;
  if (s == "info") return spdlog::level::info;
  if (s == "warn" || s == "warning") return spdlog::level::warn;
  if (s == "error") return spdlog::level::err;
  return std::nullopt;
}

}  // namespace drivegate
