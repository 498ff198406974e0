#include "status/status_view.h"

#include <algorithm>
#include <array>

namespace drivegate {

double line_busy_seconds(const Bus& bus) {
  const auto& c = bus.config();
  const auto& n = bus.counters();
  const double per_char =
      std::chrono::duration<double>(character_time(c.baud, c.parity, c.data_bits, c.stop_bits))
          .count();
  // On a one-wire line what was sent is also read back: those bytes took the line once.
  const auto chars = n.bytes_sent + n.bytes_received - (c.echo ? n.bytes_sent : 0);
  return static_cast<double>(chars) * per_char;
}

}  // namespace drivegate
