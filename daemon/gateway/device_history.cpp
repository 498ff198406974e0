// What a device records in the history (history/history.h): the audit record of each write it
// is asked for, whatever comes of it, and the events that matter to the plant as they happen
// (history_recorder.h keeps what it recorded last). Every write entry (write, write_points,
// forward, command, the failsafe's) makes an Answer with answer_to() and returns through
// answered(): a write refused at once is recorded there; one a request took is recorded when the
// request settles (finish, fail_pending).
#include <chrono>
#include <cstdio>

#include "gateway/device.h"
#include "gateway/point_values.h"

namespace drivegate {

Device::Answer Device::answer_to(const Session& session, WriteDone done, std::string asked,
                                 TimePoint now) const {
  Answer a;
  a.done = std::move(done);
  a.record.source = session.source;
  a.record.device = config_.name;
  a.record.unit = config_.unit_id;
  a.record.points = std::move(asked);
  a.since = now;
  if (session.fault_reads) a.fault_seen = session.fault_reads->fault_seen(this);
  a.access = session.access;
  return a;
}

Outcome Device::answered(Answer& answer, Outcome outcome, TimePoint now) {
  if (outcome != Outcome::ok && !answer.taken) record(answer, outcome, now);
  return outcome;
}

void Device::record(Answer& a, Outcome outcome, TimePoint now) {
  History* history = recorder_.history();
  if (history == nullptr || a.audit == Answer::Audit::none) return;
  if (a.audit == Answer::Audit::count) {
    history->audit().count(a.record.source.kind, outcome);
    return;
  }
  a.record.result = outcome;
  if (a.record.why.empty()) {
    if (outcome == Outcome::denied) {
      a.record.why = "beyond access " + std::string(to_string(a.access));
    } else if (outcome == Outcome::busy) {
      a.record.why = std::to_string(kMaxQueuedWrites) + " writes already waiting";
    } else if (outcome == Outcome::no_response && comm_lost()) {
      a.record.why = "comm lost";
    }
  }
  if (a.taken) {
    a.record.took = std::chrono::duration_cast<std::chrono::milliseconds>(now - a.since);
  }
  history->audit().record(a.record, now);
}

std::string Device::value_text(const PointSpec& spec, const Value& value) {
  if (const std::string_view label = label_of(spec, value); !label.empty()) {
    return std::string(label);
  }
  if (const auto* i = std::get_if<std::int64_t>(&value)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&value)) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", *d);
    return buf;
  }
  if (const auto* s = std::get_if<std::string>(&value)) return *s;
  return "?";
}

// The heartbeat is left out: a PLC that writes it with its command word each scan still repeats
// the same command (event_log.h), and it is the gateway's own register, not the drive's.
std::string Device::describe(std::span<const Part> parts) {
  std::string out;
  for (const Part& p : parts) {
    const CommonRow* row = p.point->row();
    if (row != nullptr && row->write == CommonWrite::heartbeat) continue;
    if (!out.empty()) out += ' ';
    out += p.point->spec.name + "=" + value_text(p.point->spec, p.value);
  }
  return out;
}

std::string Device::describe_pdu(std::span<const std::uint8_t> pdu) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out = "pdu";
  for (std::size_t i = 0; i < pdu.size() && i < 32; ++i) {
    out += ' ';
    out += kHex[pdu[i] >> 4];
    out += kHex[pdu[i] & 0xF];
  }
  if (pdu.size() > 32) out += " ...";
  return out;
}

void Device::record_changes() {
  recorder_.seen({.comm_lost = comm_lost(),
                  .ever_good = link_.health.ever_good(),
                  .online = online(),
                  .latched = failsafe_.latched(),
                  .action = config_.failsafe.action,
                  .failsafe_timeout = failsafe_.timeout(),
                  .drive = driver_->common()});
}

}  // namespace drivegate
