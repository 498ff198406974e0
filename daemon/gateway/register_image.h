// The register image of one device: the four tables a PLC reads, the adapter's points encoded
// from the driver's values and the common block's rows from a snapshot (common_block.h). Reads
// are served from it and never wait on the line. No driver, no clock: the Device says when it
// went stale (a driver call, a write applied) and hands it the values.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "drivegate/driver.h"
#include "gateway/common_block.h"
#include "gateway/register_map.h"
#include "gateway/session.h"

namespace drivegate {

class RegisterImage {
 public:
  // `map` outlives the image.
  explicit RegisterImage(const RegisterMap& map);

  // The driver may have changed since the last refresh_points(): the next read refreshes first.
  void stale() { stale_ = true; }
  [[nodiscard]] bool is_stale() const { return stale_; }
  // The adapter's points from the driver's values (by point index); the image is fresh again
  // once the holding rows are refreshed with them (refresh_common(Table::holding, ...)).
  void refresh_points(std::span<const Value> values);
  // The common block's rows of `table` as `snapshot` makes them.
  void refresh_common(Table table, const CommonSnapshot& snapshot);
  // Whether every address of the range is in the map (a read of it is served).
  [[nodiscard]] bool covers(Table table, std::uint16_t address, std::size_t count) const;
  // Copies a covered range into `out`, 32-bit values in `order`.
  void copy(Table table, std::uint16_t address, std::span<std::uint16_t> out,
            WordOrder order) const;

 private:
  [[nodiscard]] std::span<std::uint16_t> registers(Table t) { return tables_[static_cast<int>(t)]; }
  [[nodiscard]] std::span<const std::uint16_t> registers(Table t) const {
    return tables_[static_cast<int>(t)];
  }

  const RegisterMap& map_;
  std::vector<std::uint16_t> tables_[4];
  bool stale_ = true;  // the driver may have changed since the last refresh_points()
};

}  // namespace drivegate
