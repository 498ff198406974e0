// The adapter's own points: every field of the Status, Build Information and Running Limits
// payloads, with units and the document's enum and flag labels.
#pragma once

#include <cstddef>
#include <vector>

#include "drivegate/point.h"
#include "payloads.h"

namespace drivegate::unicla {

// Index of each point in points() / values().
enum PointIndex : std::size_t {
  // Status (0x01)
  kSuctionPressure,
  kDischargePressure,
  kSuctionTemperature,
  kDischargeTemperature,
  kSuctionSuperheat,
  kDischargeSuperheat,
  kRpm,
  kVolts,
  kWatts,
  kTorque,
  kOpState,
  kControlMode,
  kDemand,
  kRemoteEnable,
  kAntiShort,
  kMotorTemperature,
  kSwitchTemperature,
  kCompressorRunFlags,
  kCompressorStartFlags,
  kMotorRunFlags,
  kMotorStartFlags,
  kElectricalFlags,
  // Build Information (0x02)
  kModel,
  kSerialNumber,
  kRefrigerant,
  kOil,
  kBuildMinSpeed,
  kBuildMaxSpeed,
  kRatedVoltage,
  kRatedPower,
  kDeviceName,
  // Running Limits / RS485 Config (0x03)
  kLimitMinSpeed,
  kLimitMaxSpeed,
  kSuctionPressureLow,
  kSuctionPressureHigh,
  kDischargePressureLow,
  kDischargePressureHigh,
  kSuctionTemperatureLow,
  kSuctionTemperatureHigh,
  kDischargeTemperatureLow,
  kDischargeTemperatureHigh,
  kSuctionSuperheatLow,
  kSuctionSuperheatHigh,
  kDischargeSuperheatLow,
  kDischargeSuperheatHigh,
  kRs485DeviceId,
  kControlEnabled,
  kPointCount,
};

std::vector<PointSpec> make_points();
void fill_status(std::vector<Value>& v, const Status& s);
void fill_build_info(std::vector<Value>& v, const BuildInfo& b);
void fill_running_limits(std::vector<Value>& v, const RunningLimits& l);

}  // namespace drivegate::unicla
