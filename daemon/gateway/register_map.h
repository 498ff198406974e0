// Where every point of a device lives in the Modbus tables. The common block is the same for
// every adapter (one PLC faceplate serves all drives); the adapter's own points follow it.
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
#include <optional>
#include <vector>

#include "drivegate/point.h"

namespace drivegate {

// The common points, in register order within their table.
enum class CommonPoint : std::uint8_t {
  status,
  fault_code,
  fault_mask,
  native_fault,
  speed_rpm,
  data_age_ms,
  frames_good,
  bad_checksum,
  timeouts,
  retries,
  nacks,
  bus_exchanges,
  bus_timeouts,
  bus_echo_errors,
  bus_noise_bytes,
  bus_reopens,
  foreign_frames,
  command,
  setpoint_rpm,
  heartbeat,
  status_bit,  // discrete inputs 0..6, one per StatusBit
};

inline constexpr std::uint16_t kAdapterInputBase = 32;
inline constexpr std::uint16_t kAdapterHoldingBase = 16;
inline constexpr std::uint16_t kAdapterDiscreteBase = 16;
inline constexpr std::uint16_t kAdapterCoilBase = 0;

struct MappedPoint {
  PointSpec spec;
  std::uint16_t address = 0;
  bool common = false;
  CommonPoint common_id = CommonPoint::status;  // when common
  std::size_t index = 0;                        // adapter point index, or status bit number
};

class RegisterMap {
 public:
  explicit RegisterMap(const std::vector<PointSpec>& adapter_points);

  [[nodiscard]] const std::vector<MappedPoint>& points() const { return points_; }
  // Registers (or bits) each table needs.
  [[nodiscard]] std::uint16_t size(Table t) const { return sizes_[static_cast<int>(t)]; }
  // The point covering `address` in `t`, if any.
  [[nodiscard]] const MappedPoint* at(Table t, std::uint16_t address) const;
  // How many consecutive addresses from `address` on are mapped (0 when `address` is not): a
  // read of any range is checked in one lookup, not one per register.
  [[nodiscard]] std::size_t mapped_from(Table t, std::uint16_t address) const;

 private:
  void add(MappedPoint p);
  std::vector<MappedPoint> points_;
  std::uint16_t sizes_[4] = {0, 0, 0, 0};
  std::vector<std::int32_t> owner_[4];  // per table and address: index into points_, -1 = none
  std::vector<std::uint16_t> run_[4];   // per table and address: mapped_from()
};

}  // namespace drivegate
