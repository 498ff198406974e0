// The device side of a described protocol (`drivegate sim framed --set protocol=NAME`): it
// decodes the master's requests with the description's codec, changes its variables as the
// description's [[simulator.on]] rules say, and answers with the request's reply made from them;
// a frame whose check fails gets the description's NACK, a stream goes out every stream_ms.
// Operator commands: `state`, `set NAME VALUE` (any point or state: `set error_bits 8` trips a
// fault), `silent on|off`, `corrupt N`, `help`. No I/O: `drivegate sim` hosts it.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "codec.h"
#include "description.h"
#include "drivegate/simulator.h"
#include "state.h"

namespace drivegate::framed {

class FramedSimulator final : public Simulator {
 public:
  FramedSimulator(std::shared_ptr<const Description> d, const SimEnv& env);

  DRIVEGATE_SIMULATOR_OVERRIDES;

 private:
  Bytes answer(const Frame& request, TimePoint now);
  Bytes send(std::size_t message, std::span<const double> sent);
  void advance(TimePoint now);
  [[nodiscard]] std::string state() const;

  std::shared_ptr<const Description> d_;
  Codec codec_;
  State state_;
  Bytes rx_;
  std::optional<TimePoint> last_byte_;
  std::optional<TimePoint> last_tick_;
  std::optional<TimePoint> next_stream_;
  std::vector<double> sent_;
  bool silent_ = false;
  int corrupt_ = 0;
  long frames_ = 0;
  long rejected_ = 0;
};

}  // namespace drivegate::framed
