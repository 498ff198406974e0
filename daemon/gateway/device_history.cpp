// What a device records in the history (history/history.h): the audit record of each write it
// is asked for, whatever comes of it, and the events that matter to the plant as they happen
// (fault raised and cleared, comm lost and back, failsafe tripped and cleared, drive started and
// stopped). Every write entry (write, write_points, forward, command, the failsafe's) makes an
// Answer with answer_to() and returns through answered(): a write refused at once is recorded
// there; one a request took is recorded when the request settles (finish, fail_pending).
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
  a.access = session.access;
  return a;
}

Outcome Device::answered(Answer& answer, Outcome outcome, TimePoint now) {
  if (outcome != Outcome::ok && !answer.taken) record(answer, outcome, now);
  return outcome;
}

void Device::record(Answer& a, Outcome outcome, TimePoint now) {
  if (history_ == nullptr || a.audit == Answer::Audit::none) return;
  if (a.audit == Answer::Audit::count) {
    history_->audit().count(a.record.source.kind, outcome);
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
  history_->audit().record(a.record, now);
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

void Device::record_event(EventKind kind, std::string message,
                          std::vector<std::pair<std::string, std::string>> fields) {
  history_->record(kind, config_.name, config_.unit_id, std::move(message), std::move(fields));
}

void Device::record_changes() {
  if (history_ == nullptr) return;
  if (const bool lost = comm_lost(); lost != recorded_comm_lost_) {
    recorded_comm_lost_ = lost;
    if (lost) {
      record_event(EventKind::comm_lost, config_.name + ": comm lost: the drive stopped answering");
    } else {
      record_event(EventKind::comm_restored, config_.name + ": answers again");
    }
  }
  if (const bool latched = failsafe_.latched(); latched != recorded_latched_) {
    recorded_latched_ = latched;
    if (latched) {
      record_event(EventKind::failsafe_tripped,
                   config_.name + ": failsafe " + std::string(to_string(config_.failsafe.action)) +
                       ": no write from the PLC for " +
                       std::to_string(failsafe_.timeout().count()) + " ms",
                   {{"action", std::string(to_string(config_.failsafe.action))}});
    } else {
      record_event(EventKind::failsafe_cleared,
                   config_.name + ": failsafe reset by a run command from the PLC");
    }
  }
  // What the drive says of itself counts only while it answers: a drive that stopped answering
  // has not stopped running, nor cleared its faults. The first state heard (daemon start, the
  // device added or changed by a reload) is said as found, not as a change.
  if (comm_lost() || !link_.health.ever_good()) return;
  const bool found = !recorded_contact_;
  recorded_contact_ = true;
  const CommonState& s = driver_->common();
  record_faults(s, found);
  // Whether it runs, and with what command, once the driver knows the drive whole (online: its
  // handshake done, every block read once), as the log says it (first_contact): half a state is
  // not what the drive does.
  if (!online()) return;
  const bool found_running = !recorded_run_known_;
  recorded_run_known_ = true;
  if (s.running != recorded_running_) {
    recorded_running_ = s.running;
    const std::string how = std::string(found_running ? "found running" : "running") + " (" +
                            std::string(to_string(s.command)) + ", setpoint " +
                            std::to_string(s.setpoint_rpm) + " rpm)";
    if (s.running) {
      record_event(EventKind::drive_started, config_.name + ": " + how,
                   {{"command", std::string(to_string(s.command))},
                    {"setpoint_rpm", std::to_string(s.setpoint_rpm)},
                    {"found", found_running ? "true" : "false"}});
    } else {
      record_event(EventKind::drive_stopped, config_.name + ": stopped");
    }
  }
}

// One entry per unified fault raised or cleared (comm_lost is comm's own event), each with the
// native code in force; a native code that changes under the same faults is a fault raised anew.
void Device::record_faults(const CommonState& s, bool found) {
  char native[16];
  std::snprintf(native, sizeof native, "0x%X", static_cast<unsigned>(s.native_fault));
  const bool native_changed = s.native_fault != recorded_native_ && s.native_fault != 0;
  for (std::size_t i = 1; i < kFaultCount; ++i) {
    const auto f = static_cast<Fault>(i);
    if (f == Fault::comm_lost) continue;
    const bool now = s.faults.has(f);
    const bool was = recorded_faults_.has(f);
    if (now && (!was || native_changed)) {
      record_event(EventKind::fault_raised,
                   config_.name + ": " + (found ? "found with fault " : "fault ") +
                       std::string(to_string(f)) + " (native " + native + ")",
                   {{"fault", std::string(to_string(f))},
                    {"code", std::to_string(i)},
                    {"native", native},
                    {"found", found ? "true" : "false"}});
    } else if (!now && was) {
      record_event(EventKind::fault_cleared,
                   config_.name + ": fault " + std::string(to_string(f)) + " cleared",
                   {{"fault", std::string(to_string(f))}, {"code", std::to_string(i)}});
    }
  }
  recorded_faults_ = s.faults;
  recorded_native_ = s.native_fault;
}

}  // namespace drivegate
