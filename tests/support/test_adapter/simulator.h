// The simulated test drive: answers its address's requests (codec.h), ramps to the speed the
// last run asked for (and to 0 after a stop) in its accel time per kMaxRpm, stops at once on a
// fault, and takes operator commands: state, fault NAME, clear, silent on|off (deaf: it takes
// and answers nothing), corrupt N (the next N replies with a wrong sum), refuse N (the next N
// requests refused, not acted on).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "codec.h"
#include "drivegate/simulator.h"

namespace drivegate::testdrive {

// How fast the simulated motor's speed follows a run or a stop, either way, at the drive's
// factory accel time.
inline constexpr double kRampRpmPerSecond = kMaxRpm / (kDefaultAccel100ms / 10.0);

class TestDriveSimulator final : public Simulator {
 public:
  explicit TestDriveSimulator(std::uint8_t address) : address_(address) {}

  Bytes on_receive(ByteView rx, TimePoint now) override;
  Bytes on_tick(TimePoint now) override;
  std::string control(std::string_view line, TimePoint now) override;

 private:
  Bytes answer(const Request& r);
  [[nodiscard]] std::string state() const;

  std::uint8_t address_;
  Bytes buffer_;
  std::uint8_t state_ = 0;
  NativeFault fault_ = NativeFault::none;
  std::int16_t speed_rpm_ = 0;  // ramp_rpm_ rounded
  double ramp_rpm_ = 0;
  std::int16_t target_rpm_ = 0;
  std::uint16_t accel_100ms_ = kDefaultAccel100ms;
  std::optional<TimePoint> last_tick_;
  bool silent_ = false;
  std::uint32_t corrupt_ = 0;
  std::uint32_t refuse_ = 0;
};

}  // namespace drivegate::testdrive
