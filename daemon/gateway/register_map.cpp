#include "register_map.h"

#include <algorithm>
#include <stdexcept>

#include "drivegate/common.h"

namespace drivegate {
namespace {

PointSpec spec(std::string name, Table table, PointType type, std::string unit,
               std::string description) {
  PointSpec s;
  s.name = std::move(name);
  s.table = table;
  s.type = type;
  s.unit = std::move(unit);
  s.description = std::move(description);
  return s;
}

std::vector<Label> enum_labels(const auto& names) {
  std::vector<Label> labels;
  for (std::size_t i = 0; i < names.size(); ++i) {
    labels.push_back({std::string(names[i]), static_cast<std::uint32_t>(i)});
  }
  return labels;
}

MappedPoint common(CommonPoint id, std::uint16_t address, PointSpec s) {
  MappedPoint p;
  p.spec = std::move(s);
  p.address = address;
  p.common = true;
  p.common_id = id;
  return p;
}

}  // namespace

RegisterMap::RegisterMap(const std::vector<PointSpec>& adapter_points) {
  const auto in = Table::input;
  const auto hr = Table::holding;

  auto status = spec("status", in, PointType::u16, "", "device status bits");
  status.labels = enum_labels(kStatusBitNames);
  status.bit_labels = true;
  add(common(CommonPoint::status, 0, status));
  auto fault = spec("fault_code", in, PointType::u16, "", "most severe active fault (unified)");
  fault.labels = enum_labels(kFaultNames);
  add(common(CommonPoint::fault_code, 1, fault));
  auto mask =
      spec("fault_mask", in, PointType::u32, "", "every active fault (bit n = fault_code n)");
  mask.labels = enum_labels(kFaultNames);
  mask.bit_labels = true;
  add(common(CommonPoint::fault_mask, 2, mask));
  add(common(
      CommonPoint::native_fault, 4,
      spec("native_fault", in, PointType::u32, "", "the protocol's raw fault code or bits")));
  add(common(CommonPoint::speed_rpm, 6,
             spec("speed_rpm", in, PointType::i16, "rpm", "actual speed (negative: reverse)")));
  add(common(CommonPoint::data_age_ms, 7,
             spec("data_age_ms", in, PointType::u32, "ms",
                  "time since the last good frame (4294967295: never)")));
  add(common(CommonPoint::frames_good, 9,
             spec("frames_good", in, PointType::u32, "", "good frames received")));
  add(common(CommonPoint::bad_checksum, 11,
             spec("bad_checksum", in, PointType::u32, "", "frames dropped for a bad checksum")));
  add(common(CommonPoint::timeouts, 13,
             spec("timeouts", in, PointType::u32, "", "requests that got no reply in time")));
  add(common(CommonPoint::retries, 15,
             spec("retries", in, PointType::u32, "", "frames sent again")));
  add(common(CommonPoint::nacks, 17,
             spec("nacks", in, PointType::u32, "", "frames the device refused (NACK)")));
  // The line's own counters, the same in every device on that bus.
  add(common(CommonPoint::bus_exchanges, 19,
             spec("bus_exchanges", in, PointType::u32, "", "transactions on this device's bus")));
  add(common(CommonPoint::bus_timeouts, 21,
             spec("bus_timeouts", in, PointType::u32, "", "unanswered attempts on the bus")));
  add(common(CommonPoint::bus_echo_errors, 23,
             spec("bus_echo_errors", in, PointType::u32, "",
                  "one-wire echoes that differed from what was sent, or never came")));
  add(common(CommonPoint::bus_noise_bytes, 25,
             spec("bus_noise_bytes", in, PointType::u32, "", "bytes on the bus nobody asked for")));
  add(common(CommonPoint::bus_reopens, 27,
             spec("bus_reopens", in, PointType::u32, "", "times the port was reopened")));
  add(common(CommonPoint::foreign_frames, 29,
             spec("foreign_frames", in, PointType::u32, "",
                  "good frames for another address or sequence, dropped")));

  auto command = spec("command", hr, PointType::u16, "",
                      "write to command the drive; reads the command in force");
  command.labels = enum_labels(kCommandNames);
  command.max = static_cast<double>(kCommandNames.size() - 1);
  add(common(CommonPoint::command, 0, command));
  auto setpoint = spec("setpoint_rpm", hr, PointType::i16, "rpm",
                       "speed the next run command uses; written while running, applied at once");
  setpoint.min = -32768;
  setpoint.max = 32767;
  add(common(CommonPoint::setpoint_rpm, 1, setpoint));
  auto heartbeat = spec("heartbeat", hr, PointType::u16, "",
                        "any write proves the PLC is alive (failsafe watchdog)");
  heartbeat.max = 65535;
  add(common(CommonPoint::heartbeat, 2, heartbeat));

  for (std::size_t b = 0; b < kStatusBitNames.size(); ++b) {
    auto bit = spec(std::string("status_") + std::string(kStatusBitNames[b]), Table::discrete,
                    PointType::u16, "", "status bit " + std::to_string(b));
    MappedPoint p = common(CommonPoint::status_bit, static_cast<std::uint16_t>(b), bit);
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
    if (p.spec.table == Table::discrete || p.spec.table == Table::coil) {
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
  const int t = static_cast<int>(p.spec.table);
  const bool bits = p.spec.table == Table::discrete || p.spec.table == Table::coil;
  const std::uint16_t count = bits ? 1 : p.spec.register_count();
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

std::size_t RegisterMap::mapped_from(Table t, std::uint16_t address) const {
  const auto& run = run_[static_cast<int>(t)];
  return address < run.size() ? run[address] : 0;
}

}  // namespace drivegate
