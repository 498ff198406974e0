// Where every point of a device lives in the Modbus tables. The common block is the same for
// every adapter (common_block.h); the adapter's own points follow it, in the order the driver
// lists them, each table on its own:
//
//   input registers  0..31  common block (status, faults, speed, data age, counters)
//                   32..    adapter input points
//   holding          0..15  common block (command, setpoint_rpm, heartbeat)
//                   16..    adapter holding points
//   discrete inputs  0..15  status bits (mirror of the status register)
//                   16..    adapter discrete points
//   coils            0..    adapter coil points
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <string_view>
#include <vector>

#include "drivegate/point.h"
#include "gateway/common_block.h"

namespace drivegate {

// Where a mapped point's value comes from.
enum class PointSource : std::uint8_t {
  adapter,     // `index` into the driver's points() and values()
  common,      // `index` into kCommonBlock
  status_bit,  // `index` is the StatusBit
};

struct MappedPoint {
  PointSpec spec;
  std::uint16_t address = 0;
  PointSource source = PointSource::adapter;
  std::size_t index = 0;

  [[nodiscard]] bool common() const { return source != PointSource::adapter; }
  [[nodiscard]] const CommonRow* row() const {
    return source == PointSource::common ? &kCommonBlock[index] : nullptr;
  }
};

class RegisterMap {
 public:
  // Throws std::invalid_argument when the adapter's points overlap or overflow a table.
  explicit RegisterMap(const std::vector<PointSpec>& adapter_points);

  [[nodiscard]] const std::vector<MappedPoint>& points() const { return points_; }
  // The common block's points in table `t` (the status bits for Table::discrete), in address
  // order: the image refreshes them on every read of that table.
  [[nodiscard]] std::span<const MappedPoint> common_points(Table t) const {
    const auto& [first, count] = common_[static_cast<int>(t)];
    return std::span(points_).subspan(first, count);
  }
  // Registers (or bits) each table needs.
  [[nodiscard]] std::uint16_t size(Table t) const { return sizes_[static_cast<int>(t)]; }
  // The point covering `address` in `t`, if any.
  [[nodiscard]] const MappedPoint* at(Table t, std::uint16_t address) const;
  // How many consecutive addresses from `address` on are mapped (0 when `address` is not): a
  // read of any range is checked in one lookup, not one per register.
  [[nodiscard]] std::size_t mapped_from(Table t, std::uint16_t address) const;
  // The point named `name`, if any.
  [[nodiscard]] const MappedPoint* find(std::string_view name) const;

 private:
  void add(MappedPoint p);
  std::vector<MappedPoint> points_;
  std::uint16_t sizes_[4] = {0, 0, 0, 0};
  std::vector<std::int32_t> owner_[4];  // per table and address: index into points_, -1 = none
  std::vector<std::uint16_t> run_[4];   // per table and address: mapped_from()
  std::pair<std::size_t, std::size_t> common_[4] = {};  // per table: first index, count
};

}  // namespace drivegate
