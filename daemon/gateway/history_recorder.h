// The events one device records in the history as they happen (history/history.h): fault raised
// and cleared, comm lost and back, failsafe tripped and cleared, drive started and stopped. It
// keeps what it recorded last, to record changes only; the Device tells it what it sees after
// each driver call and tick (seen()). No driver, no clock, no logging.
//
// What the drive says of itself counts only while it answers: a drive that stopped answering has
// not stopped running, nor cleared its faults. The first state heard (daemon start, the device
// added or changed by a reload) is said as found, not as a change; whether it runs only once the
// device is online (the driver knows the drive whole), as the log says it.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "config/config.h"
#include "drivegate/driver.h"
#include "history/history.h"

namespace drivegate {

class HistoryRecorder {
 public:
  // `history` may be null: nothing recorded. It outlives the recorder.
  HistoryRecorder(History* history, std::string device, std::uint8_t unit)
      : history_(history), device_(std::move(device)), unit_(unit) {}

  // What the device shows now.
  struct Seen {
    bool comm_lost = false;
    bool ever_good = false;  // the drive's own state was heard once
    bool online = false;
    bool latched = false;  // the PLC-loss failsafe
    FailsafeAction action = FailsafeAction::stop;
    Millis failsafe_timeout{0};
    const CommonState& drive;
  };
  // Records what changed since the last call.
  void seen(const Seen& now);
  // The failsafe latched at the device a reload replaced, whose history has the trip already.
  void latched_before() { latched_ = true; }
  [[nodiscard]] History* history() const { return history_; }

 private:
  void event(EventKind kind, std::string message,
             std::vector<std::pair<std::string, std::string>> fields = {});
  void faults(const CommonState& s, bool found);

  History* history_;
  std::string device_;
  std::uint8_t unit_;
  // What was last recorded.
  bool comm_lost_ = false;
  bool contact_ = false;  // the drive's own state was heard and recorded once
  bool running_ = false;
  bool run_known_ = false;  // whether it runs was recorded once (online)
  bool latched_ = false;
  FaultSet faults_;
  std::uint32_t native_ = 0;
};

}  // namespace drivegate
