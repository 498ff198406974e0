#include "format/status_view.h"

#include <algorithm>

#include "gateway/value_codec.h"

namespace drivegate {

std::vector<std::pair<const MappedPoint*, Value>> point_values(Device& device) {
  static constexpr modbus::Session kReader{modbus::AccessLevel::read, modbus::WordOrder::big};
  std::vector<std::pair<const MappedPoint*, Value>> out;
  const auto now = Clock::now();
  for (const MappedPoint& p : device.map().points()) {
    const bool bits = p.spec.table == Table::coil || p.spec.table == Table::discrete;
    std::vector<std::uint16_t> regs(bits ? 1 : p.spec.register_count());
    if (device.read(kReader, p.spec.table, p.address, regs, now) != modbus::Exception::none) {
      continue;
    }
    if (bits) {
      out.emplace_back(&p, std::int64_t{regs[0] != 0 ? 1 : 0});
    } else if (auto v = decode_value(p.spec, regs)) {
      out.emplace_back(&p, std::move(*v));
    }
  }
  return out;
}

std::string label_of(const PointSpec& spec, const Value& value) {
  if (spec.bit_labels || spec.labels.empty()) return {};
  const auto* i = std::get_if<std::int64_t>(&value);
  if (i == nullptr) return {};
  const auto it = std::find_if(spec.labels.begin(), spec.labels.end(),
                               [&](const Label& l) { return l.value == *i; });
  return it != spec.labels.end() ? it->name : std::string();
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
