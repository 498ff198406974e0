// The motor driver side of the protocol, following the document: answers the fixed-code check
// (or 00 00 00 00 after a failed EEPROM check), runs towards the target code at 360 rpm/s,
// trips with error 0x0C after 6 s without a frame and ignores malformed frames silently.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "codec.h"
#include "drivegate/simulator.h"

namespace drivegate::mdriver {

class Mdriver2400Simulator final : public Simulator {
 public:
  explicit Mdriver2400Simulator(std::uint8_t address);

  DRIVEGATE_SIMULATOR_OVERRIDES;

  // Section 3 No.2: 360 rpm/s = 20 codes of 18 rpm a second: one code every 50 ms.
  static constexpr Millis kRampStep{50};
  // A partial frame older than this is dropped when new bytes come (a truncated frame): 24
  // characters at 2400 bps, and a master sends the bytes of one frame back to back.
  static constexpr Millis kStaleRx{100};

 private:
  Bytes handle(const Frame& f, TimePoint now);
  [[nodiscard]] std::uint8_t effective_target() const;
  void power_on();
  std::string state() const;

  std::uint8_t address_;
  Bytes buf_;
  TimePoint last_rx_{};
  std::optional<TimePoint> last_frame_;
  TimePoint last_step_{};
  bool eeprom_ok_ = true;
  bool checked_ = false;
  std::uint8_t target_ = 0;
  std::uint8_t change_ = kChangeNormal;
  std::uint8_t actual_ = 0;
  std::uint8_t error_ = 0;
  std::uint8_t temp_c_ = 0x1A;  // section 3 No.2 example: [1a] = 26 deg C
  std::array<std::uint8_t, 3> info_{};
  bool silent_ = false;
  int corrupt_ = 0;
  unsigned frames_ = 0;
  unsigned ignored_ = 0;
};

}  // namespace drivegate::mdriver
