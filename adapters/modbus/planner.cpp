#include "planner.h"

#include <algorithm>
#include <numeric>

#include "codec.h"

namespace drivegate::modbus_device {

std::uint8_t read_function(Table table) {
  switch (table) {
    case Table::coil:
      return fc::read_coils;
    case Table::discrete:
      return fc::read_discrete_inputs;
    case Table::input:
      return fc::read_input_registers;
    case Table::holding:
      return fc::read_holding_registers;
  }
  return fc::read_holding_registers;
}

std::vector<Block> plan_reads(const Profile& profile, std::span<const std::size_t> points,
                              const Skipped& skipped) {
  std::vector<std::size_t> order(points.begin(), points.end());
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const ProfilePoint& pa = profile.points[a];
    const ProfilePoint& pb = profile.points[b];
    return std::tie(pa.table, pa.address) < std::tie(pb.table, pb.address);
  });
  order.erase(std::unique(order.begin(), order.end()), order.end());

  std::vector<Block> blocks;
  for (const std::size_t i : order) {
    const ProfilePoint& p = profile.points[i];
    const bool bits = is_bit_table(p.table);
    const std::uint32_t limit = bits ? profile.modbus.max_bits : profile.modbus.max_registers;
    const std::uint32_t end = std::uint32_t{p.address} + p.width();  // one past the point
    if (!blocks.empty()) {
      Block& b = blocks.back();
      const std::uint32_t block_end = std::uint32_t{b.start} + b.count;
      // A masked point may share the register of the one before it (profile.h, mask).
      const bool near = p.address >= block_end ? p.address - block_end <= profile.modbus.max_gap
                                               : p.address >= b.start;
      // The first skipped register at or after the block's end: the gap must not hold it.
      const auto s = skipped.lower_bound({p.table, static_cast<std::uint16_t>(block_end)});
      const bool clear = s == skipped.end() || s->first != p.table || s->second >= p.address;
      if (b.table == p.table && near && clear && std::max(end, block_end) - b.start <= limit) {
        b.count = static_cast<std::uint16_t>(std::max(end, block_end) - b.start);
        b.points.push_back(i);
        continue;
      }
    }
    blocks.push_back({p.table, p.address, p.width(), {i}});
  }
  return blocks;
}

std::vector<Block> plan_reads(const Profile& profile) {
  std::vector<std::size_t> all(profile.points.size());
  std::iota(all.begin(), all.end(), std::size_t{0});
  return plan_reads(profile, all);
}

}  // namespace drivegate::modbus_device
