// The device's register image: the common block from its table (common_block.h), the adapter's
// points from the driver's values, and reads served from it, never waiting on the line.
#include <algorithm>
#include <chrono>
#include <limits>

#include "gateway/device.h"
#include "gateway/value_codec.h"

namespace drivegate {

// What changes only when the driver is called or a write is applied (both mark the image
// stale): the adapter's points and the common holding registers (command and setpoint in force,
// heartbeat).
void Device::refresh_image(TimePoint now) {
  const auto& values = driver_->values();
  for (const auto& p : map_.points()) {
    if (p.source != PointSource::adapter) continue;
    const bool bits = p.spec.table == Table::discrete || p.spec.table == Table::coil;
    auto regs = registers(p.spec.table).subspan(p.address, bits ? 1 : p.spec.register_count());
    const Value& v = p.index < values.size() ? values[p.index] : Value{};
    if (bits) {
      regs[0] = as_double(v) != 0.0 ? 1 : 0;
    } else {
      encode_value(p.spec, v, regs);
    }
  }
  refresh_common(Table::holding, now);
  image_stale_ = false;
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
  const CommonSnapshot snapshot{
      .status = status,
      .faults = faults,
      // The drive's last known faults stay in fault_mask and native_fault, but while nothing is
      // heard from it they are stale: fault_code says why nothing is current.
      .fault_code = lost ? Fault::comm_lost : most_severe(faults),
      .drive = c,
      .device = link_.counters,
      .bus = link_.bus != nullptr ? *link_.bus : no_bus,
      .data_age_ms = data_at ? static_cast<std::uint32_t>(std::clamp<long long>(
                                   std::chrono::duration_cast<Millis>(now - *data_at).count(), 0,
                                   std::numeric_limits<std::uint32_t>::max() - 1))
                             : std::numeric_limits<std::uint32_t>::max(),
      .heartbeat = heartbeat_,
  };
  for (const auto& p : map_.common_points(table)) {
    if (const CommonRow* row = p.row()) {
      encode_integer(row->type, row->value(snapshot),
                     registers(row->table).subspan(p.address, p.spec.register_count()));
    } else if (p.source == PointSource::status_bit) {
      registers(Table::discrete)[p.address] = (status >> p.index) & 1u;
    }
  }
}

Outcome Device::read(const Session& session, Table table, std::uint16_t address,
                     std::span<std::uint16_t> out, TimePoint now) {
  const auto regs = registers(table);
  if (std::size_t{address} + out.size() > regs.size() ||
      map_.mapped_from(table, address) < out.size()) {
    return Outcome::no_such_point;
  }
  if (image_stale_) refresh_image(now);
  if (table == Table::input || table == Table::discrete) refresh_common(table, now);
  std::copy_n(regs.begin() + address, out.size(), out.begin());
  if (session.word_order == WordOrder::little) {
    // Each register of a 32-bit value shows its partner's word, so a read of half a value (or
    // of a range cutting one) gives what a little-endian client expects at that address.
    for (std::size_t i = 0; i < out.size(); ++i) {
      const auto at = static_cast<std::uint16_t>(address + i);
      const MappedPoint* p = map_.at(table, at);
      if (p == nullptr || !has_word_order(p->spec)) continue;
      out[i] = regs[at == p->address ? at + 1 : at - 1];
    }
  }
  return Outcome::ok;
}

}  // namespace drivegate
