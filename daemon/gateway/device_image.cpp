// The device's register image (register_image.h): what it is made of, the adapter's points from
// the driver's values and the common block from the device's state, and reads served from it,
// never waiting on the line.
#include <algorithm>
#include <chrono>
#include <limits>

#include "gateway/device.h"

namespace drivegate {

// What changes only when the driver is called or a write is applied (both mark the image
// stale): the adapter's points and the common holding registers (command and setpoint in force,
// heartbeat).
void Device::refresh_image(TimePoint now) {
  image_.refresh_points(driver_->values());
  refresh_common(Table::holding, now);
}

// The common block's rows of `table`. The inputs (data age, the line's counters) and the status
// bits change without the driver being called, so they are computed for every read of their
// table; the holding rows with refresh_image().
void Device::refresh_common(Table table, TimePoint now) {
  if (map_.common_points(table).empty()) return;
  const CommonState& c = driver_->common();
  const bool lost = link_.health.comm_lost();
  FaultSet faults = c.faults;
  if (lost) faults.set(Fault::comm_lost);
  std::uint16_t status = 0;
  const auto bit = [&](StatusBit b, bool on) {
    if (on) status |= static_cast<std::uint16_t>(1u << static_cast<unsigned>(b));
  };
  bit(StatusBit::online, online());
  bit(StatusBit::running, c.running);
  bit(StatusBit::fault, !faults.empty());
  bit(StatusBit::warning, c.warning);
  bit(StatusBit::comm_lost, lost);
  bit(StatusBit::failsafe, failsafe_.latched());
  bit(StatusBit::command_pending, !writes_.empty());

  // The age of the drive's state: of the last frame that carried it, never of a write's echo.
  const std::optional<TimePoint> data_at = link_.health.last_data();
  const BusCounters no_bus{};
  image_.refresh_common(
      table,
      CommonSnapshot{
          .status = status,
          .faults = faults,
          // The drive's last known faults stay in fault_mask and native_fault, but while nothing
          // is heard from it they are stale: fault_code says why nothing is current.
          .fault_code = lost ? Fault::comm_lost : most_severe(faults),
          .drive = c,
          .device = link_.counters,
          .bus = link_.bus != nullptr ? *link_.bus : no_bus,
          .data_age_ms = data_at ? static_cast<std::uint32_t>(std::clamp<long long>(
                                       std::chrono::duration_cast<Millis>(now - *data_at).count(),
                                       0, std::numeric_limits<std::uint32_t>::max() - 1))
                                 : std::numeric_limits<std::uint32_t>::max(),
          .heartbeat = heartbeat_,
      });
}

Outcome Device::read(const Session& session, Table table, std::uint16_t address,
                     std::span<std::uint16_t> out, TimePoint now) {
  if (!image_.covers(table, address, out.size())) return Outcome::no_such_point;
  if (image_.is_stale()) refresh_image(now);
  if (table == Table::input || table == Table::discrete) refresh_common(table, now);
  image_.copy(table, address, out, session.word_order);
  if (session.fault_reads && shows_faults(table, address, out.size())) {
    session.fault_reads->served(this, !driver_->common().faults.empty() || comm_lost(), now);
  }
  return Outcome::ok;
}

bool Device::shows_faults(Table table, std::uint16_t address, std::size_t n) const {
  const auto shows = [](const MappedPoint& p) {
    if (p.source == PointSource::status_bit) {
      return p.index == static_cast<std::size_t>(StatusBit::fault);
    }
    const CommonRow* row = p.row();
    return row != nullptr &&
           (row->labels == CommonLabels::status_bits || row->labels == CommonLabels::faults ||
            row->labels == CommonLabels::fault_bits);
  };
  const std::size_t end = address + n;
  const auto common = map_.common_points(table);
  return std::any_of(common.begin(), common.end(), [&](const MappedPoint& p) {
    return shows(p) && address <= p.address && p.address + p.spec.address_count() <= end;
  });
}

}  // namespace drivegate
