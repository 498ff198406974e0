#include "points.h"

#include <cstdio>

#include "registers.h"

namespace drivegate::ed3100 {
namespace {

std::string hex4(std::uint16_t v, bool upper) {
  char buf[8];
  std::snprintf(buf, sizeof buf, upper ? "%04X" : "%04x", v);
  return buf;
}

PointSpec flag(std::string name, std::string description, std::vector<Label> labels) {
  PointSpec p;
  p.name = std::move(name);
  p.description = std::move(description);
  p.labels = std::move(labels);
  return p;
}

std::vector<Label> format_labels() {
  // Document, "B0 ~ B3 Parameters".
  return {{"decimals_minus_1", kFmtDecimalsMinus1},
          {"decimals_0", kFmtDecimals0},
          {"decimals_1", 2},
          {"decimals_2", 3},
          {"decimals_3", kFmtDecimals3},
          {"volt", kFmtVolt},
          {"hertz", kFmtHertz},
          {"ampere", kFmtAmpere},
          {"normal", kFmtNormal},
          {"input_terminals", kFmtInputTerminals},
          {"fault_format", kFmtFault},
          {"stopped", kFmtStopped}};
}

}  // namespace

std::vector<PointSpec> make_points(const Config& c) {
  std::vector<PointSpec> pts(kFixedCount);
  PointSpec& fault = pts[index(Fixed::fault_code)];
  fault.name = "fault_code";
  fault.description = "0x0E01 word 1: drive fault code, 0xFFFF = no fault (table not legible)";
  fault.labels = {{"no_fault", kNoFault}};

  PointSpec& state = pts[index(Fixed::state_word)];
  state.name = "state_word";
  state.description = "0x0E01 word 2: drive state bits";
  state.bit_labels = true;
  state.labels = {{"running_reverse", kStRunReverse},
                  {"phase_order_reverse", kStPhaseReverse},
                  {"commanded_reverse", kStCmdReverse},
                  {"running", kStRunning},
                  {"fault", kStFault},
                  {"digital_frequency", kStDigitalChannel},
                  {"accelerating", kStAccelerating},
                  {"decelerating", kStDecelerating}};

  pts[index(Fixed::running)] =
      flag("running", "state bit 4: the drive is running", {{"stopped", 0}, {"running", 1}});
  pts[index(Fixed::direction)] =
      flag("direction", "state bit 1: running direction", {{"forward", 0}, {"reverse", 1}});
  pts[index(Fixed::commanded_direction)] = flag(
      "commanded_direction", "state bit 3: commanded direction", {{"forward", 0}, {"reverse", 1}});
  pts[index(Fixed::accelerating)] =
      flag("accelerating", "state bit 10: accelerating", {{"no", 0}, {"yes", 1}});
  pts[index(Fixed::decelerating)] =
      flag("decelerating", "state bit 11: decelerating", {{"no", 0}, {"yes", 1}});

  PointSpec& freq = pts[index(Fixed::frequency_setpoint)];
  freq.name = "frequency_setpoint";
  freq.scale = 0.01;  // 0x2001 in 0.01 Hz (README: 0x1388 = 50.00 Hz)
  freq.unit = "Hz";
  freq.table = Table::holding;
  freq.description = "frequency reference for 0x2001; setpoint_rpm x poles / 120";
  freq.min = 0.0;
  freq.max = 655.35;  // the 16-bit register in 0.01 Hz

  for (const MonitorSel& m : c.monitors) {
    const std::string id = hex4(m.reg, false);
    const std::string ID = hex4(m.reg, true);
    PointSpec value;
    value.name = "monitor_" + id;
    value.type = PointType::f32;
    value.unit = m.unit;
    value.description = "monitor 0x" + ID + " scaled by its format word";
    PointSpec raw;
    raw.name = "monitor_" + id + "_raw";
    raw.description = "monitor 0x" + ID + " word 1, unscaled";
    PointSpec format;
    format.name = "monitor_" + id + "_format";
    format.description = "monitor 0x" + ID + " word 2: decimals, unit, stopped";
    format.bit_labels = true;
    format.labels = format_labels();
    pts.push_back(std::move(value));
    pts.push_back(std::move(raw));
    pts.push_back(std::move(format));
  }

  for (const std::uint16_t p : c.parameters) {
    char name[16];
    std::snprintf(name, sizeof name, "param_%02x_%02x", p >> 8, p & 0xFF);
    PointSpec param;
    param.name = name;
    param.table = Table::holding;
    param.description = "drive parameter at 0x" + hex4(p, true) + ", raw (read 03, written 06)";
    param.min = 0;
    param.max = 0xFFFF;
    pts.push_back(std::move(param));
  }
  return pts;
}

}  // namespace drivegate::ed3100
