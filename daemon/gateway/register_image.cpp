#include "gateway/register_image.h"

#include <algorithm>

#include "gateway/value_codec.h"

namespace drivegate {

RegisterImage::RegisterImage(const RegisterMap& map) : map_(map) {
  for (int t = 0; t < 4; ++t) tables_[t].assign(map_.size(static_cast<Table>(t)), 0);
}

void RegisterImage::refresh_points(std::span<const Value> values) {
  for (const auto& p : map_.points()) {
    if (p.source != PointSource::adapter) continue;
    const bool bits = is_bit_table(p.spec.table);
    auto regs = registers(p.spec.table).subspan(p.address, p.spec.address_count());
    const Value& v = p.index < values.size() ? values[p.index] : Value{};
    if (bits) {
      regs[0] = as_double(v) != 0.0 ? 1 : 0;
    } else {
      encode_value(p.spec, v, regs);
    }
  }
  stale_ = false;
}

void RegisterImage::refresh_common(Table table, const CommonSnapshot& snapshot) {
  for (const auto& p : map_.common_points(table)) {
    if (const CommonRow* row = p.row()) {
      encode_integer(row->type, row->value(snapshot),
                     registers(row->table).subspan(p.address, p.spec.register_count()));
    } else if (p.source == PointSource::status_bit) {
      registers(Table::discrete)[p.address] = (snapshot.status >> p.index) & 1u;
    }
  }
}

bool RegisterImage::covers(Table table, std::uint16_t address, std::size_t count) const {
  return std::size_t{address} + count <= registers(table).size() &&
         map_.mapped_from(table, address) >= count;
}

void RegisterImage::copy(Table table, std::uint16_t address, std::span<std::uint16_t> out,
                         WordOrder order) const {
  const auto regs = registers(table);
  std::copy_n(regs.begin() + address, out.size(), out.begin());
  if (order != WordOrder::little) return;
  // Each register of a 32- or 64-bit value shows the word at its mirror place in the value
  // (a 32-bit value's partner), so a read of part of a value (or of a range cutting one) gives
  // what a little-endian client expects at that address.
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto at = static_cast<std::uint16_t>(address + i);
    const MappedPoint* p = map_.at(table, at);
    if (p == nullptr || !has_word_order(p->spec)) continue;
    const std::size_t last = std::size_t{p->address} + p->spec.register_count() - 1;
    out[i] = regs[last - (at - p->address)];
  }
}

}  // namespace drivegate
