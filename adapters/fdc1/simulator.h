// A simulated FDC1 controller: streams its status every 0.5 s (both forms), follows slave-mode
// speed frames, stops after 60 s without one, echoes programming frames, and injects alarms,
// noise, corruption, silence and a deaf receiver on operator command. The protocol's timing
// (stream period, watchdog, 1 s frame window) is in codec.h.
#pragma once

#include <string>

#include "codec.h"
#include "drivegate/simulator.h"
#include "settings.h"

namespace drivegate::fdc1 {

// Shortest window `window S` accepts (a test aid: the document's window is 60 s).
inline constexpr Millis kMinWatchdog{1000};
// Simulator model, not from the document: ramp rate and current per rpm.
inline constexpr double kRampRpmPerS = 1000.0;
inline constexpr double kAmpsPerRpm = 0.0012;

class Fdc1Simulator final : public Simulator {
 public:
  explicit Fdc1Simulator(const Settings& settings);

  DRIVEGATE_SIMULATOR_OVERRIDES;

 private:
  void handle(const Speed& s, TimePoint now);
  Bytes handle(const Program& p);
  void step(TimePoint now);
  [[nodiscard]] double target_rpm() const;
  [[nodiscard]] Status status() const;
  Bytes emit(Bytes frame);
  std::string state(TimePoint now) const;

  bool started_ = false;
  TimePoint last_tick_{};
  TimePoint next_stream_{};
  TimePoint last_speed_{};
  TimePoint rx_since_{};

  Bytes rx_;
  std::uint8_t mode_ = 0;
  Speed speed_{};
  bool thermostat_ = false;  // normal modes: the thermostat asks for cooling
  bool watchdog_tripped_ = false;
  Millis watchdog_ = kSlaveWatchdog;  // `window S` shortens it for tests
  bool motor_on_ = false;
  double rpm_ = 0;
  std::uint8_t alarm_ = 0;
  double restart_left_s_ = 0;
  Program stored_{};

  bool silent_ = false;
  bool deaf_ = false;  // RxD cut: hears nothing from the master, keeps streaming
  int corrupt_ = 0;
  int mangle_ = 0;
  std::size_t noise_ = 0;
  int speeds_ = 0;
  int programs_ = 0;
  int rejected_ = 0;
  int frames_ = 0;
};

}  // namespace drivegate::fdc1
