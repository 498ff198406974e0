#include "points.h"

#include <array>
#include <string>
#include <string_view>

#include "faults.h"
#include "labels.h"

namespace drivegate::unicla {

namespace {

PointSpec real(std::string name, std::string unit, std::string description) {
  return input_point(std::move(name), PointType::f32, std::move(unit), std::move(description));
}

PointSpec word(std::string name, std::string unit, std::string description) {
  return input_point(std::move(name), PointType::u16, std::move(unit), std::move(description));
}

// An ASCII field of `chars` characters, two to a register.
PointSpec text(std::string name, std::size_t chars, std::string description) {
  return string_point(std::move(name), static_cast<std::uint16_t>(chars / 2),
                      std::move(description));
}

std::int64_t i(unsigned v) {
  return static_cast<std::int64_t>(v);
}
double d(float v) {
  return static_cast<double>(v);
}

// "Running Limits/ RS485 Config": the ranges, each the points `name`_low and `name`_high in this
// order from pt::suction_pressure_low on.
struct LimitRange {
  const char* name;
  const char* unit;
  const char* label;
  Range RunningLimits::*range;
};
constexpr std::array<LimitRange, 6> kLimitRanges = {{
    {"suction_pressure", "bar", "suction pressure", &RunningLimits::suction_pressure},
    {"discharge_pressure", "bar", "discharge pressure", &RunningLimits::discharge_pressure},
    {"suction_temperature", "degC", "suction temperature", &RunningLimits::suction_temperature},
    {"discharge_temperature", "degC", "discharge temperature",
     &RunningLimits::discharge_temperature},
    {"suction_superheat", "K", "suction superheat", &RunningLimits::suction_superheat},
    {"discharge_superheat", "K", "discharge superheat", &RunningLimits::discharge_superheat},
}};
static_assert(pt::suction_pressure_low + 2 * kLimitRanges.size() == pt::rs485_device_id);

}  // namespace

std::vector<PointSpec> make_points() {
  std::vector<PointSpec> p(pt::count);
  // "Status" table.
  p[pt::suction_pressure] =
      real("suction_pressure", "bar", "suction pressure (absolute)").trended();
  p[pt::discharge_pressure] =
      real("discharge_pressure", "bar", "discharge pressure (absolute)").trended();
  p[pt::suction_temperature] = real("suction_temperature", "degC", "suction temperature").trended();
  p[pt::discharge_temperature] =
      real("discharge_temperature", "degC", "discharge temperature").trended();
  p[pt::suction_superheat] = real("suction_superheat", "K", "suction superheat");
  p[pt::discharge_superheat] = real("discharge_superheat", "K", "discharge superheat");
  p[pt::compressor_rpm] = word("compressor_rpm", "rpm", "compressor speed as reported");
  p[pt::motor_voltage] = word("motor_voltage", "V", "motor voltage");
  p[pt::motor_power] = word("motor_power", "W", "motor power").trended();
  p[pt::motor_torque] = word("motor_torque", "Nm", "motor torque");
  p[pt::op_state] = word("op_state", "", "operating state (ED_OP_STATE)")
                        .named_values(labels_in_order(kOpStateNames));
  p[pt::control_mode] = word("control_mode", "", "control mode (ED_CONTROL_MODE)")
                            .named_values(labels_in_order(kControlModeNames));
  p[pt::demand] = word("demand", "%", "% demand");
  p[pt::remote_enable] = word("remote_enable", "", "remote enable input as reported (0 = off)");
  p[pt::anti_short] =
      word("anti_short", "", "anti-short-cycle byte as reported (no unit in the document)");
  p[pt::motor_temperature] = real("motor_temperature", "degC", "motor temperature").trended();
  p[pt::switch_temperature] = real("switch_temperature", "degC", "power switch temperature");
  p[pt::compressor_safety_run] = word("compressor_safety_run", "", "compressor safety flags - run")
                                     .named_bits(compressor_flag_labels());
  p[pt::compressor_safety_start] =
      word("compressor_safety_start", "", "compressor safety flags - start")
          .named_bits(compressor_flag_labels());
  p[pt::motor_safety_run] =
      word("motor_safety_run", "", "motor safety flags - run").named_bits(motor_flag_labels());
  p[pt::motor_safety_start] =
      word("motor_safety_start", "", "motor safety flags - start").named_bits(motor_flag_labels());
  p[pt::electrical_safety] =
      input_point("electrical_safety", PointType::u32, "", "electrical safety flags (24 bits)")
          .named_bits(electrical_flag_labels());
  // "Build Information" table.
  p[pt::model] = text("model", kModelChars, "model");
  p[pt::serial_number] = text("serial_number", kSerialChars, "serial number");
  p[pt::refrigerant] = word("refrigerant", "", "refrigerant (ED_REFRIGERANTS)")
                           .named_values(labels_in_order(kRefrigerantNames));
  p[pt::oil] = word("oil", "", "oil (ED_OILS)").named_values(labels_in_order(kOilNames));
  p[pt::build_min_speed] = word("build_min_speed", "rpm", "compressor build minimum speed");
  p[pt::build_max_speed] = word("build_max_speed", "rpm", "compressor build maximum speed");
  p[pt::rated_voltage] = word("rated_voltage", "V", "electrical build operating voltage");
  p[pt::rated_power] = word("rated_power", "W", "electrical build power rating");
  p[pt::device_name] = text("device_name", kDeviceNameChars, "device name");
  // "Running Limits/ RS485 Config" table.
  p[pt::limit_min_speed] =
      word("limit_min_speed", "rpm", "running limit: minimum speed (Set Run State floor)");
  p[pt::limit_max_speed] =
      word("limit_max_speed", "rpm", "running limit: maximum speed (Set Run State cap)");
  // Each range a low and a high point, in the table's order.
  std::size_t at = pt::suction_pressure_low;
  for (const LimitRange& r : kLimitRanges) {
    for (const std::string_view end : {"low", "high"}) {
      p[at++] = real(std::string(r.name) + "_" + std::string(end), r.unit,
                     "running limit: " + std::string(r.label) + " " + std::string(end));
    }
  }
  p[pt::rs485_device_id] = word("rs485_device_id", "", "RS485 config: device id");
  // "Control Enabled" is a flag: 0 the drive ignores writes from the bus (README.md).
  constexpr std::array<std::string_view, 2> kControlEnabled = {"disabled", "enabled"};
  p[pt::control_enabled] = word("control_enabled", "", "RS485 config: control enabled")
                               .named_values(labels_in_order(kControlEnabled));
  return p;
}

void fill_status(std::vector<Value>& v, const Status& s) {
  v[pt::suction_pressure] = d(s.suction_pressure);
  v[pt::discharge_pressure] = d(s.discharge_pressure);
  v[pt::suction_temperature] = d(s.suction_temperature);
  v[pt::discharge_temperature] = d(s.discharge_temperature);
  v[pt::suction_superheat] = d(s.suction_superheat);
  v[pt::discharge_superheat] = d(s.discharge_superheat);
  v[pt::compressor_rpm] = i(s.rpm);
  v[pt::motor_voltage] = i(s.volts);
  v[pt::motor_power] = i(s.watts);
  v[pt::motor_torque] = i(s.torque);
  v[pt::op_state] = i(s.op_state);
  v[pt::control_mode] = i(s.control_mode);
  v[pt::demand] = i(s.demand);
  v[pt::remote_enable] = i(s.remote_enable);
  v[pt::anti_short] = i(s.anti_short);
  v[pt::motor_temperature] = d(s.motor_temperature);
  v[pt::switch_temperature] = d(s.switch_temperature);
  v[pt::compressor_safety_run] = i(s.compressor_run_flags);
  v[pt::compressor_safety_start] = i(s.compressor_start_flags);
  v[pt::motor_safety_run] = i(s.motor_run_flags);
  v[pt::motor_safety_start] = i(s.motor_start_flags);
  v[pt::electrical_safety] = i(s.electrical_flags);
}

void fill_build_info(std::vector<Value>& v, const BuildInfo& b) {
  v[pt::model] = b.model;
  v[pt::serial_number] = b.serial;
  v[pt::refrigerant] = i(b.refrigerant);
  v[pt::oil] = i(b.oil);
  v[pt::build_min_speed] = i(b.min_speed);
  v[pt::build_max_speed] = i(b.max_speed);
  v[pt::rated_voltage] = i(b.voltage);
  v[pt::rated_power] = i(b.power);
  v[pt::device_name] = b.device_name;
}

void fill_running_limits(std::vector<Value>& v, const RunningLimits& l) {
  v[pt::limit_min_speed] = i(l.min_speed);
  v[pt::limit_max_speed] = i(l.max_speed);
  std::size_t at = pt::suction_pressure_low;
  for (const LimitRange& r : kLimitRanges) {
    v[at++] = d((l.*r.range).low);
    v[at++] = d((l.*r.range).high);
  }
  v[pt::rs485_device_id] = i(l.device_id);
  v[pt::control_enabled] = i(l.control_enabled);
}

}  // namespace drivegate::unicla
