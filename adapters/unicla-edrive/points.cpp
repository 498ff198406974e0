#include "points.h"

#include <span>
#include <string_view>

#include "labels.h"

namespace drivegate::unicla {

namespace {

std::vector<Label> labels_of(std::span<const std::string_view> names) {
  std::vector<Label> out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!names[i].empty()) out.push_back({std::string(names[i]), static_cast<std::uint32_t>(i)});
  }
  return out;
}

PointSpec input(std::string name, PointType type, std::string unit, std::string description) {
  PointSpec p;
  p.name = std::move(name);
  p.table = Table::input;
  p.type = type;
  p.unit = std::move(unit);
  p.description = std::move(description);
  return p;
}

PointSpec real(std::string name, std::string unit, std::string description) {
  return input(std::move(name), PointType::f32, std::move(unit), std::move(description));
}

PointSpec word(std::string name, std::string unit, std::string description) {
  return input(std::move(name), PointType::u16, std::move(unit), std::move(description));
}

PointSpec enumeration(std::string name, std::string description,
                      std::span<const std::string_view> names) {
  PointSpec p = word(std::move(name), "", std::move(description));
  p.labels = labels_of(names);
  return p;
}

PointSpec flags(std::string name, PointType type, std::string description,
                std::span<const std::string_view> names) {
  PointSpec p = input(std::move(name), type, "", std::move(description));
  p.labels = labels_of(names);
  p.bit_labels = true;
  return p;
}

PointSpec text(std::string name, std::size_t chars, std::string description) {
  PointSpec p = input(std::move(name), PointType::string, "", std::move(description));
  p.string_registers = static_cast<std::uint16_t>(chars / 2);  // two characters a register
  return p;
}

std::int64_t i(unsigned v) {
  return static_cast<std::int64_t>(v);
}
double d(float v) {
  return static_cast<double>(v);
}

}  // namespace

std::vector<PointSpec> make_points() {
  std::vector<PointSpec> p;
  p.reserve(kPointCount);
  // Status (0x01), "Status" table.
  p.push_back(real("suction_pressure", "bar", "suction pressure (absolute)"));
  p.push_back(real("discharge_pressure", "bar", "discharge pressure (absolute)"));
  p.push_back(real("suction_temperature", "degC", "suction temperature"));
  p.push_back(real("discharge_temperature", "degC", "discharge temperature"));
  p.push_back(real("suction_superheat", "K", "suction superheat"));
  p.push_back(real("discharge_superheat", "K", "discharge superheat"));
  p.push_back(word("compressor_rpm", "rpm", "compressor speed as reported"));
  p.push_back(word("motor_voltage", "V", "motor voltage"));
  p.push_back(word("motor_power", "W", "motor power"));
  p.push_back(word("motor_torque", "Nm", "motor torque"));
  p.push_back(enumeration("op_state", "operating state (ED_OP_STATE)", kOpStateNames));
  p.push_back(enumeration("control_mode", "control mode (ED_CONTROL_MODE)", kControlModeNames));
  p.push_back(word("demand", "%", "% demand"));
  p.push_back(word("remote_enable", "", "remote enable input as reported (0 = off)"));
  p.push_back(
      word("anti_short", "", "anti-short-cycle byte as reported (no unit in the document)"));
  p.push_back(real("motor_temperature", "degC", "motor temperature"));
  p.push_back(real("switch_temperature", "degC", "power switch temperature"));
  p.push_back(flags("compressor_safety_run", PointType::u16, "compressor safety flags - run",
                    kCompressorFlagNames));
  p.push_back(flags("compressor_safety_start", PointType::u16, "compressor safety flags - start",
                    kCompressorFlagNames));
  p.push_back(
      flags("motor_safety_run", PointType::u16, "motor safety flags - run", kMotorFlagNames));
  p.push_back(
      flags("motor_safety_start", PointType::u16, "motor safety flags - start", kMotorFlagNames));
  p.push_back(flags("electrical_safety", PointType::u32, "electrical safety flags (24 bits)",
                    kElectricalFlagNames));
  // Build Information (0x02), "Build Information" table.
  p.push_back(text("model", kModelChars, "model"));
  p.push_back(text("serial_number", kSerialChars, "serial number"));
  p.push_back(enumeration("refrigerant", "refrigerant (ED_REFRIGERANTS)", kRefrigerantNames));
  p.push_back(enumeration("oil", "oil (ED_OILS)", kOilNames));
  p.push_back(word("build_min_speed", "rpm", "compressor build minimum speed"));
  p.push_back(word("build_max_speed", "rpm", "compressor build maximum speed"));
  p.push_back(word("rated_voltage", "V", "electrical build operating voltage"));
  p.push_back(word("rated_power", "W", "electrical build power rating"));
  p.push_back(text("device_name", kDeviceNameChars, "device name"));
  // Running Limits / RS485 Config (0x03).
  p.push_back(word("limit_min_speed", "rpm", "running limit: minimum speed (Set Run State floor)"));
  p.push_back(word("limit_max_speed", "rpm", "running limit: maximum speed (Set Run State cap)"));
  p.push_back(real("suction_pressure_low", "bar", "running limit: suction pressure low"));
  p.push_back(real("suction_pressure_high", "bar", "running limit: suction pressure high"));
  p.push_back(real("discharge_pressure_low", "bar", "running limit: discharge pressure low"));
  p.push_back(real("discharge_pressure_high", "bar", "running limit: discharge pressure high"));
  p.push_back(real("suction_temperature_low", "degC", "running limit: suction temperature low"));
  p.push_back(real("suction_temperature_high", "degC", "running limit: suction temperature high"));
  p.push_back(
      real("discharge_temperature_low", "degC", "running limit: discharge temperature low"));
  p.push_back(
      real("discharge_temperature_high", "degC", "running limit: discharge temperature high"));
  p.push_back(real("suction_superheat_low", "K", "running limit: suction superheat low"));
  p.push_back(real("suction_superheat_high", "K", "running limit: suction superheat high"));
  p.push_back(real("discharge_superheat_low", "K", "running limit: discharge superheat low"));
  p.push_back(real("discharge_superheat_high", "K", "running limit: discharge superheat high"));
  p.push_back(word("rs485_device_id", "", "RS485 config: device id"));
  PointSpec control = word("control_enabled", "", "RS485 config: control enabled");
  control.labels = {{"disabled", 0}, {"enabled", 1}};
  p.push_back(std::move(control));
  return p;
}

void fill_status(std::vector<Value>& v, const Status& s) {
  v[kSuctionPressure] = d(s.suction_pressure);
  v[kDischargePressure] = d(s.discharge_pressure);
  v[kSuctionTemperature] = d(s.suction_temperature);
  v[kDischargeTemperature] = d(s.discharge_temperature);
  v[kSuctionSuperheat] = d(s.suction_superheat);
  v[kDischargeSuperheat] = d(s.discharge_superheat);
  v[kRpm] = i(s.rpm);
  v[kVolts] = i(s.volts);
  v[kWatts] = i(s.watts);
  v[kTorque] = i(s.torque);
  v[kOpState] = i(s.op_state);
  v[kControlMode] = i(s.control_mode);
  v[kDemand] = i(s.demand);
  v[kRemoteEnable] = i(s.remote_enable);
  v[kAntiShort] = i(s.anti_short);
  v[kMotorTemperature] = d(s.motor_temperature);
  v[kSwitchTemperature] = d(s.switch_temperature);
  v[kCompressorRunFlags] = i(s.compressor_run_flags);
  v[kCompressorStartFlags] = i(s.compressor_start_flags);
  v[kMotorRunFlags] = i(s.motor_run_flags);
  v[kMotorStartFlags] = i(s.motor_start_flags);
  v[kElectricalFlags] = i(s.electrical_flags);
}

void fill_build_info(std::vector<Value>& v, const BuildInfo& b) {
  v[kModel] = b.model;
  v[kSerialNumber] = b.serial;
  v[kRefrigerant] = i(b.refrigerant);
  v[kOil] = i(b.oil);
  v[kBuildMinSpeed] = i(b.min_speed);
  v[kBuildMaxSpeed] = i(b.max_speed);
  v[kRatedVoltage] = i(b.voltage);
  v[kRatedPower] = i(b.power);
  v[kDeviceName] = b.device_name;
}

void fill_running_limits(std::vector<Value>& v, const RunningLimits& l) {
  v[kLimitMinSpeed] = i(l.min_speed);
  v[kLimitMaxSpeed] = i(l.max_speed);
  v[kSuctionPressureLow] = d(l.suction_pressure.low);
  v[kSuctionPressureHigh] = d(l.suction_pressure.high);
  v[kDischargePressureLow] = d(l.discharge_pressure.low);
  v[kDischargePressureHigh] = d(l.discharge_pressure.high);
  v[kSuctionTemperatureLow] = d(l.suction_temperature.low);
  v[kSuctionTemperatureHigh] = d(l.suction_temperature.high);
  v[kDischargeTemperatureLow] = d(l.discharge_temperature.low);
  v[kDischargeTemperatureHigh] = d(l.discharge_temperature.high);
  v[kSuctionSuperheatLow] = d(l.suction_superheat.low);
  v[kSuctionSuperheatHigh] = d(l.suction_superheat.high);
  v[kDischargeSuperheatLow] = d(l.discharge_superheat.low);
  v[kDischargeSuperheatHigh] = d(l.discharge_superheat.high);
  v[kRs485DeviceId] = i(l.device_id);
  v[kControlEnabled] = i(l.control_enabled);
}

}  // namespace drivegate::unicla
