#include "status/status_view.h"

#include <algorithm>
#include <array>

namespace drivegate {

std::string_view label_of(const PointSpec& spec, const Value& value) {
  if (spec.bit_labels || spec.labels.empty()) return {};
  const auto* i = std::get_if<std::int64_t>(&value);
  if (i == nullptr) return {};
  const auto it = std::find_if(spec.labels.begin(), spec.labels.end(),
                               [&](const Label& l) { return l.value == *i; });
  return it != spec.labels.end() ? std::string_view(it->name) : std::string_view();
}

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
