#include "gateway/register_map.h"

#include <algorithm>
#include <stdexcept>

#include "drivegate/common.h"

namespace drivegate {

RegisterMap::RegisterMap(const std::vector<PointSpec>& adapter_points) {
  std::uint16_t next[4] = {0, 0, 0, 0};
  for (std::size_t i = 0; i < kCommonBlock.size(); ++i) {
    MappedPoint p;
    p.spec = common_spec(kCommonBlock[i]);
    p.source = PointSource::common;
    p.index = i;
    auto& at = next[static_cast<int>(p.spec.table)];
    p.address = at;
    at = static_cast<std::uint16_t>(at + p.spec.register_count());
    add(std::move(p));
  }
  for (std::size_t b = 0; b < kStatusBitNames.size(); ++b) {
    MappedPoint p;
    p.spec = status_bit_spec(b);
    p.address = static_cast<std::uint16_t>(b);
    p.source = PointSource::status_bit;
    p.index = b;
    add(std::move(p));
  }

  sizes_[static_cast<int>(Table::input)] = kAdapterInputBase;
  sizes_[static_cast<int>(Table::holding)] = kAdapterHoldingBase;
  sizes_[static_cast<int>(Table::discrete)] = kAdapterDiscreteBase;
  sizes_[static_cast<int>(Table::coil)] = kAdapterCoilBase;
  for (std::size_t i = 0; i < adapter_points.size(); ++i) {
    MappedPoint p;
    p.spec = adapter_points[i];
    p.index = i;
    p.address = sizes_[static_cast<int>(p.spec.table)];
    if (is_bit_table(p.spec.table)) {
      p.spec.type = PointType::u16;  // one bit
    }
    add(std::move(p));
  }

  for (int t = 0; t < 4; ++t) {
    const auto& owner = owner_[t];
    auto& run = run_[t];
    run.assign(owner.size(), 0);
    for (std::size_t a = owner.size(); a-- > 0;) {
      if (owner[a] < 0) continue;
      run[a] = static_cast<std::uint16_t>(a + 1 < owner.size() ? run[a + 1] + 1 : 1);
    }
  }
}

void RegisterMap::add(MappedPoint p) {
  // The common block's points come first, each table's together (kCommonBlock is in table order,
  // then the status bits): common_points() is one slice per table.
  if (p.common()) {
    auto& [first, count] = common_[static_cast<int>(p.spec.table)];
    if (count == 0) first = points_.size();
    if (first + count != points_.size()) {
      throw std::logic_error("kCommonBlock must list each table's rows together");
    }
    ++count;
  }
  // Names are how the register map, `drivegate write` and every client that reads it by name find
  // a point: one name, one point.
  if (p.spec.name.empty()) throw std::invalid_argument("a point has no name");
  if (find(p.spec.name) != nullptr) {
    throw std::invalid_argument("point name '" + p.spec.name + "' is used twice" +
                                (find(p.spec.name)->common() ? " (by the common block)" : ""));
  }
  const int t = static_cast<int>(p.spec.table);
  const std::uint16_t count = p.spec.address_count();
  if (count == 0) throw std::invalid_argument("point '" + p.spec.name + "' has no registers");
  const std::uint32_t end = std::uint32_t{p.address} + count;
  if (end > 0xFFFF) throw std::invalid_argument("register map overflows at '" + p.spec.name + "'");
  auto& owner = owner_[t];
  if (owner.size() < end) owner.resize(end, -1);
  for (std::uint32_t a = p.address; a < end; ++a) {
    if (owner[a] != -1) {
      throw std::invalid_argument("point '" + p.spec.name + "' overlaps '" +
                                  points_[static_cast<std::size_t>(owner[a])].spec.name + "'");
    }
    owner[a] = static_cast<std::int32_t>(points_.size());
  }
  sizes_[t] = std::max<std::uint16_t>(sizes_[t], static_cast<std::uint16_t>(end));
  points_.push_back(std::move(p));
}

const MappedPoint* RegisterMap::at(Table t, std::uint16_t address) const {
  const auto& owner = owner_[static_cast<int>(t)];
  if (address >= owner.size() || owner[address] < 0) return nullptr;
  return &points_[static_cast<std::size_t>(owner[address])];
}

const MappedPoint* RegisterMap::find(std::string_view name) const {
  for (const auto& p : points_) {
    if (p.spec.name == name) return &p;
  }
  return nullptr;
}

std::size_t RegisterMap::mapped_from(Table t, std::uint16_t address) const {
  const auto& run = run_[static_cast<int>(t)];
  return address < run.size() ? run[address] : 0;
}

}  // namespace drivegate
