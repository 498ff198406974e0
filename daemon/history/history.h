// What happened and when, in one place the daemon owns across reloads (docs/audit.md): the
// event history (event_log.h), the audit trail that records every command into it
// (command_audit.h), and the drives' trends (trend_store.h). Devices, the gateway and the
// daemon record here; the HTTP side and `drivegate events` read it.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "history/command_audit.h"
#include "history/event_log.h"
#include "history/trend_store.h"

namespace drivegate {

class History {
 public:
  // `journal` (may be null) gets each command record (command_audit.h).
  explicit History(HistoryBounds bounds = {}, EventLog::WallClock wall = &EventLog::system_ms,
                   JournalWriter* journal = nullptr, std::size_t samples = kTrendSamples)
      : events_(bounds, std::move(wall)), audit_(events_, journal), trends_(samples) {}
  // `each` entries on every shelf of the event history.
  explicit History(std::size_t each, EventLog::WallClock wall = &EventLog::system_ms,
                   JournalWriter* journal = nullptr, std::size_t samples = kTrendSamples)
      : History(HistoryBounds{each, each, each}, std::move(wall), journal, samples) {}
  History(const History&) = delete;
  History& operator=(const History&) = delete;

  // One of the plant's events (not a command: those go through audit()).
  void record(EventKind kind, std::string device, std::uint8_t unit, std::string message,
              std::vector<std::pair<std::string, std::string>> fields = {}) {
    events_.add(Event{.kind = kind,
                      .device = std::move(device),
                      .unit = unit,
                      .message = std::move(message),
                      .fields = std::move(fields)});
  }

  EventLog& events() { return events_; }
  [[nodiscard]] const EventLog& events() const { return events_; }
  CommandAudit& audit() { return audit_; }
  [[nodiscard]] const CommandAudit& audit() const { return audit_; }
  TrendStore& trends() { return trends_; }
  [[nodiscard]] const TrendStore& trends() const { return trends_; }

 private:
  EventLog events_;
  CommandAudit audit_;
  TrendStore trends_;
};

}  // namespace drivegate
