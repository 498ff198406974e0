// What a device records in the history (history/history.h): the audit record of each write it
// is asked for, whatever comes of it, and the events that matter to the plant as they happen
// (fault raised and cleared, comm lost and back, failsafe tripped and cleared, drive started and
// stopped). Every write entry (write, write_points, forward, command, the failsafe's) makes an
// Answer with answer_to() and returns through answered(): a write refused at once is recorded
// there; one a request took is recorded when the request settles (finish, fail_pending).
#include <chrono>
#include <cstdio>

#include "gateway/device.h"
#include "gateway/device_request.h"
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

std::string Device::describe(std::span<const Part> parts) {
  std::string out;
  for (const Part& p : parts) {
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
  const CommonState& s = driver_->common();
  if (const Fault f = most_severe(s.faults); f != recorded_fault_) {
    recorded_fault_ = f;
    char native[16];
    std::snprintf(native, sizeof native, "0x%X", static_cast<unsigned>(s.native_fault));
    if (f == Fault::none) {
      record_event(EventKind::fault_cleared, config_.name + ": faults cleared");
    } else {
      record_event(EventKind::fault_raised,
                   config_.name + ": fault " + std::string(to_string(f)) + " (native " + native +
                       ")",
                   {{"fault", std::string(to_string(f))},
                    {"code", std::to_string(static_cast<unsigned>(f))},
                    {"native", native}});
    }
  }
  if (const bool running = s.running && !comm_lost(); running != recorded_running_) {
    recorded_running_ = running;
    if (running) {
      record_event(EventKind::drive_started,
                   config_.name + ": running (" + std::string(to_string(s.command)) +
                       ", setpoint " + std::to_string(s.setpoint_rpm) + " rpm)",
                   {{"command", std::string(to_string(s.command))},
                    {"setpoint_rpm", std::to_string(s.setpoint_rpm)}});
    } else {
      record_event(EventKind::drive_stopped, config_.name + ": stopped");
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
}

}  // namespace drivegate
