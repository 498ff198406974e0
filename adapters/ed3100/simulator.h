// A simulated ED3100: answers 03 / 06 / 10 the way the document's examples do (the register
// echo where a byte count belongs, by default), ramps its output frequency, trips on demand.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>

#include "codec.h"
#include "drivegate/simulator.h"

namespace drivegate::ed3100 {

class Ed3100Simulator final : public Simulator {
 public:
  Ed3100Simulator(std::uint8_t address, ReadForm form);

  DRIVEGATE_SIMULATOR_OVERRIDES;

 private:
  Bytes handle(const Request& r);
  Bytes read(const Request& r);
  // Validates a write of `value` to `reg`: nullopt when the drive takes it, else the exception.
  [[nodiscard]] std::optional<std::uint8_t> check(std::uint16_t reg, std::uint16_t value) const;
  void store(std::uint16_t reg, std::uint16_t value);
  [[nodiscard]] std::pair<std::uint16_t, std::uint16_t> monitor(std::uint16_t reg) const;
  [[nodiscard]] std::uint16_t state_word() const;
  [[nodiscard]] bool commanded_run() const;
  [[nodiscard]] std::string state() const;
  Bytes finish(Bytes reply);

  std::uint8_t address_;
  ReadForm form_;
  Bytes rx_;
  std::optional<TimePoint> last_rx_;
  std::optional<TimePoint> last_tick_;

  std::map<std::uint16_t, std::uint16_t> params_;
  std::map<std::uint16_t, std::pair<std::uint16_t, std::uint16_t>> monitor_override_;
  std::uint16_t command_;     // 0x2000 as last written
  std::uint16_t reference_;   // 0x2001, 0.01 Hz
  std::uint16_t output_ = 0;  // output frequency, 0.01 Hz
  bool running_ = false;
  bool rotating_reverse_ = false;
  bool commanded_reverse_;
  bool accelerating_ = false;
  bool decelerating_ = false;
  std::uint16_t fault_;
  bool silent_ = false;
  // Writes refused with exception 04, as by a drive whose command source is not the bus.
  bool locked_ = false;
  int corrupt_ = 0;
};

}  // namespace drivegate::ed3100
