#include "logging.h"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/base_sink.h>
#include <spdlog/sinks/stdout_sinks.h>
#include <sys/stat.h>
#include <sys/uio.h>
// Else sd_journal_sendv() adds CODE_FILE= / CODE_LINE= of this sink to every entry.
#define SD_JOURNAL_SUPPRESS_LOCATION
#include <systemd/sd-journal.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>

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

// The name after `prefix` up to ": " (or, with stop_at_space, up to the first space).
std::string_view name_after(std::string_view text, std::string_view prefix, bool stop_at_space) {
  if (!text.starts_with(prefix)) return {};
  text.remove_prefix(prefix.size());
  const auto end = stop_at_space ? text.find_first_of(" :") : text.find(": ");
  return end == std::string_view::npos ? std::string_view{} : text.substr(0, end);
}

// Entries with their fields, over the journal's native protocol (sd_journal_sendv(3)). When
// sending fails (sd_journal_sendv() < 0) the line goes to stderr, which is the journal's stream,
// with the "<N>" priority prefix journald reads there (sd-daemon(3)).
class JournalSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  void set_devices(std::vector<DeviceTag> devices) {
    const std::lock_guard<std::mutex> lock(mutex_);
    devices_ = std::move(devices);
  }

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    const std::string_view text(msg.payload.data(), msg.payload.size());
    const int priority = syslog_priority(msg.level);
    const LogSubject subject = log_subject(text, devices_);
    std::vector<std::string> fields;
    fields.reserve(6);
    fields.push_back("MESSAGE=" + std::string(text));
    fields.push_back("PRIORITY=" + std::to_string(priority));
    fields.push_back("SYSLOG_IDENTIFIER=" +
                     std::string(msg.logger_name.data(), msg.logger_name.size()));
    if (!subject.device.empty()) fields.push_back("DEVICE=" + subject.device);
    if (!subject.bus.empty()) fields.push_back("BUS=" + subject.bus);
    if (subject.unit) fields.push_back("UNIT=" + std::to_string(*subject.unit));
    std::vector<iovec> iov;
    iov.reserve(fields.size());
    for (auto& f : fields) iov.push_back({f.data(), f.size()});
    if (sd_journal_sendv(iov.data(), static_cast<int>(iov.size())) < 0) {
      std::fprintf(stderr, "<%d>%.*s\n", priority, static_cast<int>(text.size()), text.data());
    }
  }
  void flush_() override { std::fflush(stderr); }

 private:
  std::vector<DeviceTag> devices_;  // guarded by base_sink's mutex_
};

}  // namespace

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

LogSubject log_subject(std::string_view message, const std::vector<DeviceTag>& devices) {
  constexpr std::string_view kDevice = "device ";
  constexpr std::string_view kBus = "bus ";
  LogSubject s;
  if (const auto dev = name_after(message, kDevice, false); !dev.empty()) {
    s.device = dev;
  } else if (const auto bus = name_after(message, kBus, false); !bus.empty()) {
    s.bus = bus;
    // "bus B: device D did not answer": D ends at a space, unless a known name is longer.
    std::string_view rest = message.substr(kBus.size() + bus.size() + 2);
    if (rest.starts_with(kDevice)) {
      rest.remove_prefix(kDevice.size());
      s.device = rest.substr(0, rest.find_first_of(" :"));
      for (const auto& d : devices) {
        const bool ends = rest.size() == d.name.size() || rest[d.name.size()] == ' ' ||
                          rest[d.name.size()] == ':';
        if (rest.starts_with(d.name) && ends && d.name.size() > s.device.size()) s.device = d.name;
      }
    }
  }
  for (const auto& d : devices) {
    if (s.device.empty() || d.name != s.device) continue;
    if (s.bus.empty()) s.bus = d.bus;
    s.unit = d.unit_id;
  }
  return s;
}

void describe_devices(spdlog::logger& log, std::vector<DeviceTag> devices) {
  for (const auto& sink : log.sinks()) {
    if (auto* journal = dynamic_cast<JournalSink*>(sink.get())) journal->set_devices(devices);
  }
}

void describe_devices(spdlog::logger& log, const Config& config) {
  std::vector<DeviceTag> tags;
  tags.reserve(config.devices.size());
  for (const auto& d : config.devices) tags.push_back({d.name, d.bus, d.unit_id});
  describe_devices(log, std::move(tags));
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
