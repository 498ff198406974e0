// The common block (README, "Register map"): the points every drive has at the same addresses, so
// that one PLC faceplate serves all of them. Declared once, here, as a table: the register map
// lays the points out from it (register_map.cpp) and the register image fills them from the same
// rows (device_image.cpp), so adding a counter is one row. The discrete inputs 0..6 mirror the
// status bits, one per StatusBit (include/drivegate/common.h).
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "bus/link.h"
#include "drivegate/common.h"
#include "drivegate/driver.h"
#include "drivegate/point.h"

namespace drivegate {

// Where the adapter's own points start, table by table: the common block is reserved below.
inline constexpr std::uint16_t kAdapterInputBase = 32;
inline constexpr std::uint16_t kAdapterHoldingBase = 16;
inline constexpr std::uint16_t kAdapterDiscreteBase = 16;
inline constexpr std::uint16_t kAdapterCoilBase = 0;

// What a common point's value is made of at one moment.
struct CommonSnapshot {
  std::uint16_t status;      // StatusBit n is bit n
  FaultSet faults;           // the active set, comm_lost included
  Fault fault_code;          // what `fault_code` shows
  const CommonState& drive;  // the driver's
  const DeviceCounters& device;
  const BusCounters& bus;
  std::uint32_t data_age_ms;  // 0xFFFFFFFF: never heard
  std::uint16_t heartbeat;
};

// Which of the unified vocabulary's names a common point's labels are.
enum class CommonLabels : std::uint8_t { none, status_bits, faults, fault_bits, commands };

// What a write to a common holding point does.
enum class CommonWrite : std::uint8_t { none, command, setpoint, heartbeat };

struct CommonRow {
  Table table;
  const char* name;
  PointType type;
  const char* unit;
  const char* description;
  std::int64_t (*value)(const CommonSnapshot&);
  CommonLabels labels = CommonLabels::none;
  CommonWrite write = CommonWrite::none;
  double min = 0.0;  // writable rows: the engineering range a write may carry
  double max = 0.0;
  bool counter = false;  // only ever grows (wrapping at 2^32): a Prometheus counter, not a gauge
  // The value the row holds while what it shows is not known; the status JSON and MQTT then show
  // null, /metrics NaN (README, "Register map").
  std::optional<std::int64_t> unknown = std::nullopt;
};

// A row that counts events (see CommonRow::counter).
constexpr CommonRow counting(CommonRow row) {
  row.counter = true;
  return row;
}

// A row whose value may be unknown, holding `mark` then (CommonRow::unknown).
constexpr CommonRow unknown_as(CommonRow row, std::int64_t mark) {
  row.unknown = mark;
  return row;
}

// What speed_rpm holds while the speed is not known (CommonState::speed_unknown, or a speed
// beyond what the register carries): the one i16 value no known speed takes.
inline constexpr std::int64_t kSpeedUnknown = -kMaxSpeedRpm - 1;

// In address order within each table: a row's address is the sum of the register counts of the
// rows of its table above it.
inline constexpr std::array kCommonBlock = {
    CommonRow{Table::input, "status", PointType::u16, "", "device status bits",
              [](const CommonSnapshot& s) -> std::int64_t { return s.status; },
              CommonLabels::status_bits},
    CommonRow{Table::input, "fault_code", PointType::u16, "", "most severe active fault (unified)",
              [](const CommonSnapshot& s) -> std::int64_t {
                return static_cast<std::int64_t>(s.fault_code);
              },
              CommonLabels::faults},
    CommonRow{Table::input, "fault_mask", PointType::u32, "",
              "every active fault (bit n = fault_code n)",
              [](const CommonSnapshot& s) -> std::int64_t { return s.faults.bits(); },
              CommonLabels::fault_bits},
    CommonRow{Table::input, "native_fault", PointType::u32, "",
              "the protocol's raw fault code or bits",
              [](const CommonSnapshot& s) -> std::int64_t { return s.drive.native_fault; }},
    unknown_as(CommonRow{Table::input, "speed_rpm", PointType::i16, "rpm",
                         "actual speed (negative: reverse; -32768: unknown)",
                         [](const CommonSnapshot& s) -> std::int64_t {
                           const std::int32_t rpm = s.drive.speed_rpm;
                           const bool carried = rpm >= -kMaxSpeedRpm && rpm <= kMaxSpeedRpm;
                           return s.drive.speed_unknown || !carried ? kSpeedUnknown : rpm;
                         }},
               kSpeedUnknown),
    CommonRow{Table::input, "data_age_ms", PointType::u32, "ms",
              "time since the last reply carrying the drive's state (4294967295: never)",
              [](const CommonSnapshot& s) -> std::int64_t { return s.data_age_ms; }},
    counting(
        CommonRow{Table::input, "frames_good", PointType::u32, "", "good frames received",
                  [](const CommonSnapshot& s) -> std::int64_t { return s.device.frames_good; }}),
    counting(CommonRow{
        Table::input, "bad_checksum", PointType::u32, "", "frames dropped for a bad checksum",
        [](const CommonSnapshot& s) -> std::int64_t { return s.device.bad_checksum; }}),
    counting(CommonRow{Table::input, "timeouts", PointType::u32, "",
                       "requests that got no reply in time",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.device.timeouts; }}),
    counting(CommonRow{Table::input, "retries", PointType::u32, "", "frames sent again",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.device.retries; }}),
    counting(CommonRow{Table::input, "nacks", PointType::u32, "",
                       "frames the device refused (NACK)",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.device.nacks; }}),
    // The line's own counters, the same in every device on that bus.
    counting(CommonRow{Table::input, "bus_exchanges", PointType::u32, "",
                       "transactions on this device's bus",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.bus.exchanges; }}),
    counting(CommonRow{Table::input, "bus_timeouts", PointType::u32, "",
                       "unanswered attempts on the bus",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.bus.timeouts; }}),
    counting(CommonRow{Table::input, "bus_echo_errors", PointType::u32, "",
                       "one-wire echoes that differed from what was sent, or never came",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.bus.echo_errors; }}),
    counting(CommonRow{Table::input, "bus_noise_bytes", PointType::u32, "",
                       "bytes on the bus nobody asked for",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.bus.noise_bytes; }}),
    counting(CommonRow{Table::input, "bus_reopens", PointType::u32, "",
                       "times the port was reopened",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.bus.reopens; }}),
    counting(CommonRow{Table::input, "foreign_frames", PointType::u32, "",
                       "good frames for another address or sequence, dropped",
                       [](const CommonSnapshot& s) -> std::int64_t { return s.device.foreign; }}),

    CommonRow{Table::holding, "command", PointType::u16, "",
              "write to command the drive; reads the command in force",
              [](const CommonSnapshot& s) -> std::int64_t {
                return static_cast<std::int64_t>(s.drive.command);
              },
              CommonLabels::commands, CommonWrite::command, 0.0,
              static_cast<double>(kCommandNames.size() - 1)},
    CommonRow{
        Table::holding, "setpoint_rpm", PointType::i16, "rpm",
        "speed the next run uses; written while running, in force once the drive confirmed it",
        [](const CommonSnapshot& s) -> std::int64_t { return s.drive.setpoint_rpm; },
        CommonLabels::none, CommonWrite::setpoint, -32768.0, 32767.0},
    CommonRow{Table::holding, "heartbeat", PointType::u16, "",
              "any write proves the PLC is alive (failsafe watchdog)",
              [](const CommonSnapshot& s) -> std::int64_t { return s.heartbeat; },
              CommonLabels::none, CommonWrite::heartbeat, 0.0, 65535.0},
};

// Registers the common block's rows take in `table`.
constexpr std::uint16_t common_size(Table table) {
  std::uint16_t n = 0;
  for (const CommonRow& r : kCommonBlock) {
    if (r.table == table) n = static_cast<std::uint16_t>(n + registers_of(r.type));
  }
  return n;
}
static_assert(common_size(Table::input) <= kAdapterInputBase, "common inputs overflow their block");
static_assert(common_size(Table::holding) <= kAdapterHoldingBase,
              "common holding registers overflow their block");
static_assert(kStatusBitNames.size() <= kAdapterDiscreteBase, "status bits overflow their block");

// The PointSpec a row stands for (labels filled in from the unified vocabulary).
PointSpec common_spec(const CommonRow& row);
// The PointSpec of discrete input `bit`: "status_online", ...
PointSpec status_bit_spec(std::size_t bit);

}  // namespace drivegate
