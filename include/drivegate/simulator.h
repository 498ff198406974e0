// A simulated device: the other end of an adapter's protocol, for commissioning before hardware
// arrives and for the gateway's own end-to-end tests. Like a Driver it does no I/O; `drivegate
// sim` hosts it on a pseudo-terminal (or a real port) and owns echo, turnaround and wire timing.
//
// DRIVEGATE_SIMULATOR_OVERRIDES declares, in a simulator's class, the three overrides every
// simulator has; it adds what else it has after it.
#pragma once

#include <string>
#include <string_view>

#include "drivegate/driver.h"

// The overrides every simulator declares: the master's bytes, time passing, the operator.
#define DRIVEGATE_SIMULATOR_OVERRIDES                    \
  Bytes on_receive(ByteView rx, TimePoint now) override; \
  Bytes on_tick(TimePoint now) override;                 \
  std::string control(std::string_view line, TimePoint now) override

namespace drivegate {

struct SimEnv {
  std::uint32_t address = 0;  // the native address it answers to
  Options options;            // the adapter's device options (defaults filled in)
};

class Simulator {
 public:
  virtual ~Simulator() = default;
  // Bytes from the master, in whatever chunks the line delivered them. Returns the reply bytes
  // (empty: stay silent).
  virtual Bytes on_receive(ByteView rx, TimePoint now) = 0;
  // Time passes: returns unsolicited bytes (streams) and applies time-driven behaviour
  // (tripping after bus silence, ramps). Called at least every 50 ms.
  virtual Bytes on_tick(TimePoint now) = 0;
  // One operator command line, e.g. "fault stall", "silent on", "corrupt 3", "state".
  // Returns the answer to print; an unknown command answers with "error: ..." and the list.
  virtual std::string control(std::string_view line, TimePoint now) = 0;
};

}  // namespace drivegate
