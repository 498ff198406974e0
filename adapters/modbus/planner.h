// The read plan of a profile: the fewest requests that read a set of points, joining points of a
// table that are near one another into one block, within the device's limit per read and reading
// through unused registers up to [modbus] max_gap, never through a register the slave refuses.
// Pure.
#pragma once

#include <cstddef>
#include <cstdint>
#include <set>
#include <span>
#include <utility>
#include <vector>

#include "profile.h"

namespace drivegate::modbus_device {

// One read request: FC 01 / 02 / 03 / 04 by table (Application Protocol 6.1 - 6.4).
struct Block {
  Table table = Table::holding;
  std::uint16_t start = 0;          // the first register (or bit) read
  std::uint16_t count = 0;          // registers (or bits) read
  std::vector<std::size_t> points;  // indices into Profile::points, by address

  friend bool operator==(const Block&, const Block&) = default;
};

// The function code that reads `table` (Application Protocol 6.1 - 6.4).
std::uint8_t read_function(Table table);

// The data bytes a read reply to `b` carries: its bits packed eight a byte, or two a register
// (Application Protocol 6.1 - 6.4).
constexpr std::size_t data_bytes(const Block& b) {
  return is_bit_table(b.table) ? (b.count + 7u) / 8u : 2u * b.count;
}

// Registers (or bits) a read must not cover, by table: the slave refuses them (exception 02).
using Skipped = std::set<std::pair<Table, std::uint16_t>>;

// Blocks reading `points` (indices into profile.points), table by table (coils, discrete inputs,
// input registers, holding registers) and by address. Greedy from the lowest address, which
// gives the fewest blocks: a point joins the block before it when the registers (or bits) between
// them are at most max_gap, none of them is `skipped`, and the block stays within max_registers
// (max_bits for bit tables).
std::vector<Block> plan_reads(const Profile& profile, std::span<const std::size_t> points,
                              const Skipped& skipped = {});

// Every point of the profile.
std::vector<Block> plan_reads(const Profile& profile);

}  // namespace drivegate::modbus_device
