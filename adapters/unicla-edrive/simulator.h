// A simulated eDrive: answers Status, Build Information and Running Limits reads for its own
// device id (and the global 0xFF), follows Set Run State within its running limits, and takes
// faults, flags, silence and corrupt CRCs from the operator (see README.md, "Simulator").
#pragma once

#include <cstdint>
#include <string>

#include "codec.h"
#include "drivegate/simulator.h"
#include "op_state.h"
#include "payloads.h"

namespace drivegate::unicla {

class EDriveSimulator final : public Simulator {
 public:
  EDriveSimulator(std::uint8_t address, ByteOrder order);

  DRIVEGATE_SIMULATOR_OVERRIDES;

  // For tests: the status it would report now.
  [[nodiscard]] Status status() const;

 private:
  void handle(const Frame& f, TimePoint now, Bytes& out);
  void set_run_state(std::uint16_t speed, TimePoint now);
  void acknowledge();
  void trip(OpState state);
  Bytes reply(const Frame& request, Bytes payload);
  std::string state_line() const;
  std::string fault_command(std::string_view arg);
  std::string flags_command(std::string_view word, std::string_view value);

  std::uint8_t address_;
  ByteOrder order_;
  Bytes rx_;
  BuildInfo build_;
  RunningLimits limits_;

  OpState state_ = OpState::stopped;
  std::uint8_t raw_state_ = 0;  // an injected op state outside the named ones
  bool raw_ = false;
  double rpm_ = 0;
  std::uint16_t target_ = 0;
  TimePoint starting_since_{};
  TimePoint last_tick_{};
  bool ticked_ = false;

  std::uint16_t compressor_run_ = 0;
  std::uint16_t compressor_start_ = 0;
  std::uint16_t motor_run_ = 0;
  std::uint16_t motor_start_ = 0;
  std::uint32_t electrical_ = 0;

  bool silent_ = false;
  bool sticky_ = false;
  int corrupt_ = 0;
  int reads_ = 0;
  int writes_ = 0;
};

}  // namespace drivegate::unicla
