#include "gateway/history_recorder.h"

#include <cstdio>

namespace drivegate {

void HistoryRecorder::event(EventKind kind, std::string message,
                            std::vector<std::pair<std::string, std::string>> fields) {
  history_->record(kind, device_, unit_, std::move(message), std::move(fields));
}

void HistoryRecorder::seen(const Seen& now) {
  if (history_ == nullptr) return;
  if (now.comm_lost != comm_lost_) {
    comm_lost_ = now.comm_lost;
    if (now.comm_lost) {
      event(EventKind::comm_lost, device_ + ": comm lost: the drive stopped answering");
    } else {
      event(EventKind::comm_restored, device_ + ": answers again");
    }
  }
  if (now.latched != latched_) {
    latched_ = now.latched;
    if (now.latched) {
      event(EventKind::failsafe_tripped,
            device_ + ": failsafe " + std::string(to_string(now.action)) +
                ": no write from the PLC for " + std::to_string(now.failsafe_timeout.count()) +
                " ms",
            {{"action", std::string(to_string(now.action))}});
    } else {
      event(EventKind::failsafe_cleared,
            device_ + ": failsafe reset by a run command from the PLC");
    }
  }
  if (now.comm_lost || !now.ever_good) return;
  const bool found = !contact_;
  contact_ = true;
  const CommonState& s = now.drive;
  faults(s, found);
  // Whether it runs, and with what command, once the driver knows the drive whole (online: its
  // handshake done, every block read once): half a state is not what the drive does.
  if (!now.online) return;
  const bool found_running = !run_known_;
  run_known_ = true;
  if (s.running != running_) {
    running_ = s.running;
    const std::string how = std::string(found_running ? "found running" : "running") + " (" +
                            std::string(to_string(s.command)) + ", setpoint " +
                            std::to_string(s.setpoint_rpm) + " rpm)";
    if (s.running) {
      event(EventKind::drive_started, device_ + ": " + how,
            {{"command", std::string(to_string(s.command))},
             {"setpoint_rpm", std::to_string(s.setpoint_rpm)},
             {"found", found_running ? "true" : "false"}});
    } else {
      event(EventKind::drive_stopped, device_ + ": stopped");
    }
  }
}

// One entry per unified fault raised or cleared (comm_lost is comm's own event), each with the
// native code in force; a native code that changes under the same faults is a fault raised anew.
void HistoryRecorder::faults(const CommonState& s, bool found) {
  char native[16];
  std::snprintf(native, sizeof native, "0x%X", static_cast<unsigned>(s.native_fault));
  const bool native_changed = s.native_fault != native_ && s.native_fault != 0;
  for (std::size_t i = 1; i < kFaultCount; ++i) {
    const auto f = static_cast<Fault>(i);
    if (f == Fault::comm_lost) continue;
    const bool now = s.faults.has(f);
    const bool was = faults_.has(f);
    if (now && (!was || native_changed)) {
      event(EventKind::fault_raised,
            device_ + ": " + (found ? "found with fault " : "fault ") + std::string(to_string(f)) +
                " (native " + native + ")",
            {{"fault", std::string(to_string(f))},
             {"code", std::to_string(i)},
             {"native", native},
             {"found", found ? "true" : "false"}});
    } else if (!now && was) {
      event(EventKind::fault_cleared, device_ + ": fault " + std::string(to_string(f)) + " cleared",
            {{"fault", std::string(to_string(f))}, {"code", std::to_string(i)}});
    }
  }
  faults_ = s.faults;
  native_ = s.native_fault;
}

}  // namespace drivegate
