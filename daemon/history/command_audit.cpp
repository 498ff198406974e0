#include "history/command_audit.h"

#include <algorithm>
#include <cctype>

namespace drivegate {

namespace {

std::string describe(const Source& s) {
  std::string out(to_string(s.kind));
  if (!s.client.empty()) out += " " + s.client;
  if (!s.listener.empty()) out += " on " + s.listener;
  if (!s.subject.empty()) out += ", certificate \"" + s.subject + "\"";
  if (!s.role.empty()) out += ", role " + s.role;
  return out;
}

// Where a write went, as a record says it.
std::string describe_where(const std::string& device, std::uint8_t unit, SourceKind source) {
  // A Modbus client addresses a unit; a DCMD names a device, and one not configured has no unit
  // (its name is in `why`).
  if (!device.empty()) return device + " (unit " + std::to_string(unit) + ")";
  if (source == SourceKind::mqtt) return "an unknown device";
  return "unit " + std::to_string(unit);
}

// Whether writes from `kind` are folded in a flood: the network's clients. The gateway's own
// cannot flood, and are the ones an engineer looks for after a trip; `drivegate write` is an
// operator at the console.
bool folds(SourceKind kind) {
  switch (kind) {
    case SourceKind::modbus:
    case SourceKind::modbus_tls:
    case SourceKind::modbus_serial:
    case SourceKind::modbus_rtu_tcp:
    case SourceKind::mqtt:
      return true;
    case SourceKind::cli:
    case SourceKind::failsafe:
    case SourceKind::shutdown:
    case SourceKind::gateway:
      break;
  }
  return false;
}

std::string seconds_text(std::int64_t ms) {
  const std::int64_t tenths = (std::max<std::int64_t>(ms, 0) + 50) / 100;
  return std::to_string(tenths / 10) + "." + std::to_string(tenths % 10) + " s";
}

}  // namespace

std::string result_name(Outcome o) {
  std::string name(to_string(o));
  std::replace(name.begin(), name.end(), ' ', '_');
  return name;
}

std::string describe_registers(Table table, std::uint16_t address,
                               std::span<const std::uint16_t> values) {
  std::string out(kTableNames.at(static_cast<std::size_t>(table)));
  out += " " + std::to_string(address);
  if (values.size() > 1) out += ".." + std::to_string(address + values.size() - 1);
  out += " =";
  for (const std::uint16_t v : values) {
    if (out.size() > kMaxText) break;  // the history cuts it there anyway
    out += " " + std::to_string(v);
  }
  return out;
}

Event command_event(const CommandRecord& r) {
  Event e;
  e.kind = EventKind::command;
  e.device = r.device;
  e.unit = r.unit;
  e.message = "write to " + describe_where(r.device, r.unit, r.source.kind) + " from " +
              describe(r.source) + ": " + (r.points.empty() ? std::string("(nothing)") : r.points) +
              ": " + std::string(to_string(r.result));
  if (!r.why.empty()) e.message += " (" + r.why + ")";
  if (r.took) e.message += ", " + std::to_string(r.took->count()) + " ms";
  const auto add = [&e](const char* name, const std::string& value) {
    if (!value.empty()) e.fields.emplace_back(name, value);
  };
  add("source", std::string(to_string(r.source.kind)));
  add("listener", r.source.listener);
  add("client", r.source.client);
  add("subject", r.source.subject);
  add("role", r.source.role);
  add("points", r.points);
  add("result", result_name(r.result));
  add("why", r.why);
  if (r.took) add("took_ms", std::to_string(r.took->count()));
  return e;
}

std::vector<std::string> journal_fields(const Event& e) {
  std::vector<std::string> out;
  out.reserve(e.fields.size() + 3);
  out.push_back("EVENT=" + std::string(to_string(e.kind)));
  if (!e.device.empty()) out.push_back("DEVICE=" + e.device);
  if (e.unit != 0) out.push_back("UNIT=" + std::to_string(e.unit));
  for (const auto& [name, value] : e.fields) {
    std::string f;
    f.reserve(name.size() + 1 + value.size());
    for (const char c : name) f += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    f += '=';
    f += value;
    out.push_back(std::move(f));
  }
  return out;
}

Event summary_event(const FoldSummary& s) {
  Event e;
  e.kind = EventKind::command;
  e.device = s.device;
  e.unit = s.unit;
  std::string where = describe_where(s.device, s.unit, s.source);
  std::string who = std::string(to_string(s.source)) + " " + s.client + " on " + s.listener;
  if (s.spread != FoldSpread::points) where = "several devices";
  if (s.spread == FoldSpread::source) {
    who = "several " + std::string(to_string(s.source)) + " clients";
  }
  e.message = std::to_string(s.folded) + " write" + (s.folded == 1 ? "" : "s") + " to " + where +
              " from " + who + " in " + seconds_text(s.last_ms - s.since_ms) +
              ", folded into this record: " + (s.points.empty() ? "" : s.points + ": ") +
              std::string(to_string(s.result)) +
              "; the last: " + (s.last_points.empty() ? std::string("(nothing)") : s.last_points);
  if (s.spread != FoldSpread::points) {
    e.message += " to " + describe_where(s.last_device, s.last_unit, s.source);
  }
  if (s.spread == FoldSpread::source) e.message += " from " + describe(s.last_source);
  if (!s.last_why.empty()) e.message += " (" + s.last_why + ")";
  const auto add = [&e](const char* name, const std::string& value) {
    if (!value.empty()) e.fields.emplace_back(name, value);
  };
  const bool one_client = s.spread != FoldSpread::source;
  add("source", std::string(to_string(s.source)));
  add("listener", one_client ? s.listener : s.last_source.listener);
  add("client", one_client ? s.client : s.last_source.client);
  add("subject", s.last_source.subject);
  add("role", s.last_source.role);
  add("points", s.last_points);
  add("result", result_name(s.result));
  add("why", s.last_why);
  add("folded", std::to_string(s.folded));
  add("since_ms", std::to_string(s.since_ms));
  add("last_ms", std::to_string(s.last_ms));
  if (s.spread == FoldSpread::client) add("spread", "client");
  if (s.spread == FoldSpread::source) add("spread", "source");
  return e;
}

CommandAudit::CommandAudit(EventLog& history, JournalWriter* journal, FoldLimits limits)
    : history_(history), journal_(journal), accepted_(limits), refused_(limits) {}

void CommandAudit::count(SourceKind source, Outcome result) {
  ++counts_.n[static_cast<std::size_t>(source)][static_cast<std::size_t>(result)];
}

void CommandAudit::record(const CommandRecord& r, TimePoint now) {
  count(r.source.kind, r.result);
  Event e = command_event(r);
  // A repeat costs nothing: counted in the entry it repeats, whatever its result.
  if (history_.repeat(e)) return;
  if (folds(r.source.kind)) {
    CommandFold& fold = r.result == Outcome::ok ? accepted_ : refused_;
    if (!fold.admit(r, now, history_.now_ms())) {
      ++counts_
            .folded_n[static_cast<std::size_t>(r.source.kind)][static_cast<std::size_t>(r.result)];
      // The device's newest entry is no longer the last thing it was asked.
      history_.interrupt(r.device);
      return;
    }
  }
  write(std::move(e));
}

void CommandAudit::flush(TimePoint now, bool all) {
  for (CommandFold* fold : {&accepted_, &refused_}) {
    for (const FoldSummary& s : fold->due(now, all)) write(summary_event(s));
  }
}

void CommandAudit::write(Event e) {
  if (journal_ != nullptr) journal_->info(e.message, journal_fields(e));
  history_.add(std::move(e));
}

}  // namespace drivegate
