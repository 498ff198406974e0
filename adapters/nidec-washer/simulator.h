// A simulated Nidec washer inverter (spec V07): answers every frame of section 5, NACKs bad
// frames (5.16), latches and clears the section 8 faults, and stops the motor after 6 s of bus
// silence (section 7).
#pragma once

#include <array>
#include <optional>
#include <string>

#include "codec.h"
#include "drivegate/simulator.h"

namespace drivegate::nidec {

class NidecWasherSimulator final : public Simulator {
 public:
  // Section 2: one inverter per wire and no address in the frame; the platform and empty raw
  // weight come with the ping (5.1), so no device option concerns the inverter's side.
  NidecWasherSimulator() = default;

  DRIVEGATE_SIMULATOR_OVERRIDES;

 private:
  enum class Motion : std::uint8_t {
    stopped,
    cw,
    ccw,
    agitation,
    spin,
    free_shaft_spin,
    stopping,
    braking
  };

  static Motion rotation(Mode m);
  Bytes handle(const Request& r, TimePoint now);
  Bytes status_reply(Mode m, std::uint8_t last = 0) const;
  Bytes send(Bytes frame);
  void start(Motion m, const Request& r, TimePoint now);
  void trip(std::uint8_t bits, TimePoint now);
  void advance(TimePoint now);
  [[nodiscard]] std::uint16_t speed() const;
  [[nodiscard]] std::uint8_t weight() const;
  [[nodiscard]] std::uint16_t raw_weight() const;
  [[nodiscard]] std::string state() const;

  // Bus
  Bytes rx_;
  std::optional<TimePoint> last_byte_;
  bool silent_ = false;
  int corrupt_ = 0;
  int nack_ = 0;
  long frames_ = 0;
  long nacks_sent_ = 0;
  bool comm_fault_ = false;

  // Inverter
  bool pinged_ = false;
  std::uint8_t platform_ = 0;
  std::uint16_t empty_raw_ = 0;
  std::uint16_t version_ = 0x0107;
  Motion motion_ = Motion::stopped;
  std::uint16_t target_ = 0;
  double speed_ = 0.0;
  double ramp_ = 0.0;  // rpm per second towards target_
  AgitationTiming agitation_;
  TimePoint phase_start_{};
  std::optional<TimePoint> last_tick_;
  std::uint8_t faults_ = 0;
  std::array<std::optional<TimePoint>, 8> clear_at_{};  // per fault bit
  bool forced_brake_ = false;
  std::uint16_t dc_bus_ = 311;
  std::uint8_t load_ = 35;  // x 100 g
  std::optional<TimePoint> weighing_since_;
  bool weighed_ = false;
  std::uint8_t fabric_ = 2;
};

}  // namespace drivegate::nidec
