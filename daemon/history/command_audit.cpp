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
  // A Modbus client addresses a unit; a DCMD names a device, and one not configured has no unit
  // (its name is in `why`).
  std::string where;
  if (!r.device.empty()) {
    where = r.device + " (unit " + std::to_string(r.unit) + ")";
  } else if (r.source.kind == SourceKind::mqtt) {
    where = "an unknown device";
  } else {
    where = "unit " + std::to_string(r.unit);
  }
  e.message = "write to " + where + " from " + describe(r.source) + ": " +
              (r.points.empty() ? std::string("(nothing)") : r.points) + ": " +
              std::string(to_string(r.result));
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

CommandAudit::CommandAudit(EventLog& history, JournalWriter* journal)
    : history_(history), journal_(journal) {}

void CommandAudit::count(SourceKind source, Outcome result) {
  ++counts_.n[static_cast<std::size_t>(source)][static_cast<std::size_t>(result)];
}

void CommandAudit::record(const CommandRecord& r, TimePoint now) {
  count(r.source.kind, r.result);
  Event e = command_event(r);
  // A repeat costs nothing: counted in the entry it repeats, whatever its result.
  if (history_.repeat(e)) return;
  // The gateway's own writes (the failsafe's, shutdown's) are never held back: no client can
  // cause them in a flood, and they are the ones an engineer looks for after a trip.
  const bool clients = r.source.kind != SourceKind::failsafe &&
                       r.source.kind != SourceKind::shutdown &&
                       r.source.kind != SourceKind::gateway;
  if (r.result != Outcome::ok && clients) {
    const auto held = refusals_[static_cast<std::size_t>(r.source.kind)]
                               [static_cast<std::size_t>(r.result)]
                                   .admit(now);
    if (!held) return;
    if (*held > 0) {
      e.message += " (" + std::to_string(*held) + " more " + std::string(to_string(r.result)) +
                   " from " + std::string(to_string(r.source.kind)) + " clients not recorded)";
      e.fields.emplace_back("held", std::to_string(*held));
    }
  }
  const std::vector<std::string> fields = journal_fields(e);
  if (journal_ != nullptr) journal_->info(e.message, fields);
  history_.add(std::move(e));
}

}  // namespace drivegate
