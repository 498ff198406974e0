// The audit trail (IEC 62443-3-3 SR 2.8, auditable events): one record of every write that
// reaches the gateway, from any northbound or the gateway itself, accepted or refused: when, from
// whom (source.h), to which device, which points and values, the result and how long the drive
// took. Each goes to the journal at info level with structured fields and into the history
// (event_log.h). Devices record here (gateway/device.h); the daemon owns it across reloads.
//
// What is not recorded one by one, and why (each is still counted, in counts() and /metrics):
// - a network client's writes past its allowance, accepted or refused (command_fold.h): folded,
//   per client address and listener, device, points and result, into one summary record an
//   interval that says how many came, when, and the last of them. A flood must neither flood the
//   journal (journald drops a service's messages past its rate limit, the ones that matter with
//   them) nor push older records out of the history. The refused and the accepted have separate
//   allowances, so that a client without write rights cannot fold the records of one with them.
//   The gateway's own writes (failsafe, shutdown, on_start) and `drivegate write`'s are never
//   folded;
// - a repeat of the device's newest entry (the same points, values, source and result), which
//   that entry counts (event_log.h): a PLC writing its command word every scan;
// - a write of the heartbeat alone: the gateway's own register, written to prove the PLC is
//   there, not a command to the drive (docs/safety.md).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "drivegate/driver.h"
#include "drivegate/point.h"
#include "gateway/outcome.h"
#include "gateway/source.h"
#include "history/command_fold.h"
#include "history/event_log.h"
#include "history/journal_writer.h"

namespace drivegate {

struct CommandRecord {
  Source source;
  std::string device;
  std::uint8_t unit = 0;
  // What was asked: "command=run_forward setpoint_rpm=1500" once validated, else the registers
  // as they came ("holding 0..1 = 1 1500").
  std::string points;
  Outcome result = Outcome::ok;
  std::string why;  // more than the result says, if anything ("needs operate, has read")
  // From accepted to answered; none: answered at once, before the drive was involved.
  std::optional<std::chrono::milliseconds> took;
};

// Writes by source and result, every one counted (drivegate_writes_total in /metrics), and those
// of them folded into a summary record (drivegate_audit_folded_total).
struct CommandCounts {
  using Table =
      std::array<std::array<std::uint64_t, kOutcomeNames.size()>, kSourceKindNames.size()>;
  Table n{};
  Table folded_n{};
  [[nodiscard]] std::uint64_t at(SourceKind s, Outcome o) const {
    return n[static_cast<std::size_t>(s)][static_cast<std::size_t>(o)];
  }
  [[nodiscard]] std::uint64_t folded(SourceKind s, Outcome o) const {
    return folded_n[static_cast<std::size_t>(s)][static_cast<std::size_t>(o)];
  }
};

// An outcome as the journal's RESULT= and the history's "result" say it: "no_such_point" (the
// metrics' `result` label likewise).
std::string result_name(Outcome o);

// The registers a client asked to write, as they came: "holding 0..1 = 1 1500".
std::string describe_registers(Table table, std::uint16_t address,
                               std::span<const std::uint16_t> values);

// The record as a history entry: message and fields (source, listener, client, subject, role,
// points, result, why, took_ms; those without a value left out).
Event command_event(const CommandRecord& r);
// A summary of folded records as a history entry: the fields of the last one's record (its
// client's address only, unless it is its source kind's overflow), with "folded" (how many),
// "since_ms" and "last_ms" (the first's and the last's time), and "spread" for an overflow
// ("client": every device and point of the client; "source": every client of the kind).
Event summary_event(const FoldSummary& s);
// The journal fields of a history entry: each field upper-cased (SOURCE=, CLIENT=, ...), with
// EVENT=, DEVICE= and UNIT=.
std::vector<std::string> journal_fields(const Event& e);

class CommandAudit {
 public:
  // `journal` may be null (nothing but the history).
  CommandAudit(EventLog& history, JournalWriter* journal, FoldLimits limits = {});

  // One write's record; `now` paces the clients' records (command_fold.h).
  void record(const CommandRecord& r, TimePoint now);
  // Records the summaries of folded writes due at `now`; every one pending if `all` (the daemon
  // stopping). The daemon calls it about once a second.
  void flush(TimePoint now, bool all = false);
  // A write counted but not recorded (the heartbeat alone).
  void count(SourceKind source, Outcome result);
  [[nodiscard]] const CommandCounts& counts() const { return counts_; }

 private:
  // Into the journal and the history.
  void write(Event e);

  EventLog& history_;
  JournalWriter* journal_;
  CommandCounts counts_;
  CommandFold accepted_;  // the clients' writes carried out
  CommandFold refused_;   // ... and refused: an allowance of their own
};

}  // namespace drivegate
