// A simulated serial line between the bus engine and simulated devices (the adapters' own
// Simulators, as `drivegate sim` hosts them on a pty). Every frame takes its time on the wire at
// the line's character time; every simulator hears every frame (multi-drop) and answers after
// `turnaround`; a one-wire line gives the master its own bytes back; unsolicited bytes (streams)
// come from the simulators' ticks every 10 ms. The bytes in both directions are recorded with
// their time, so tests assert exactly what was on the wire.
#pragma once

#include <chrono>
#include <functional>
#include <vector>

#include "bus/bus_engine.h"
#include "drivegate/simulator.h"
#include "sim_clock.h"

namespace drivegate::test {

class SimLine final : public BusLine {
 public:
  struct Frame {
    TimePoint at;  // when its first byte went on the wire (master frames queue in the UART)
    Bytes bytes;
  };

  SimLine(SimClock& clock, std::chrono::nanoseconds char_time, bool echo)
      : clock_(clock), char_time_(char_time), echo_(echo) {}

  void attach(BusEngine& engine) { engine_ = &engine; }
  void add(Simulator& sim) { sims_.push_back(&sim); }
  // Starts the simulators' ticks.
  void start();

  void send(ByteView frame) override;

  // Time a device takes to start answering.
  std::chrono::nanoseconds turnaround{std::chrono::milliseconds(5)};
  // Bytes from the devices pass through this first (to corrupt or drop them): empty = lost.
  std::function<Bytes(Bytes)> device_filter;
  // Whether the devices hear the master (false: a cut line; the master still hears its echo).
  bool connected = true;

  std::vector<Frame> sent;     // master -> devices, resends included, in order
  std::vector<Frame> answers;  // devices -> master, as they left the devices (before the filter)

 private:
  [[nodiscard]] std::chrono::nanoseconds on_wire(std::size_t n) const {
    return char_time_ * static_cast<long>(n);
  }
  void from_devices(Bytes bytes, TimePoint start);
  void tick();

  SimClock& clock_;
  std::chrono::nanoseconds char_time_;
  bool echo_;
  BusEngine* engine_ = nullptr;
  std::vector<Simulator*> sims_;
  bool ticking_ = false;
  TimePoint uart_free_{};  // when the master's last byte has left the UART
};

}  // namespace drivegate::test
