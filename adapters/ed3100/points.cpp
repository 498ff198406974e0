#include "points.h"

#include <cstdio>
#include <string>

#include "faults.h"
#include "registers.h"

namespace drivegate::ed3100 {
namespace {

std::string hex4(std::uint16_t v, bool upper) {
  char buf[8];
  std::snprintf(buf, sizeof buf, upper ? "%04X" : "%04x", v);
  return buf;
}

// One bit of the state word as a 0/1 point.
PointSpec flag(std::string name, std::string description, const char* off, const char* on) {
  return input_point(std::move(name), PointType::u16, "", std::move(description))
      .named_values({{off, 0}, {on, 1}});
}

// Document, "B0 ~ B3 Parameters".
std::vector<Label> format_labels() {
  return {{"decimals_minus_1", kFmtDecimalsMinus1},
          {"decimals_0", kFmtDecimals0},
          {"decimals_1", kFmtDecimals1},
          {"decimals_2", kFmtDecimals2},
          {"decimals_3", kFmtDecimals3},
          {"volt", kFmtVolt},
          {"hertz", kFmtHertz},
          {"ampere", kFmtAmpere},
          {"normal", kFmtNormal},
          {"input_terminals", kFmtInputTerminals},
          {"fault_format", kFmtFault},
          {"stopped", kFmtStopped}};
}

// Document, "B4 ~ B7 Parameters".
std::vector<Label> state_labels() {
  return {{"running_reverse", kStRunReverse},
          {"phase_order_reverse", kStPhaseReverse},
          {"commanded_reverse", kStCmdReverse},
          {"running", kStRunning},
          {"fault", kStFault},
          {"digital_frequency", kStDigitalChannel},
          {"accelerating", kStAccelerating},
          {"decelerating", kStDecelerating}};
}

}  // namespace

std::vector<PointSpec> make_points(const Settings& s) {
  std::vector<PointSpec> pts(pt::count);
  pts[pt::drive_fault_code] =
      input_point("drive_fault_code", PointType::u16, "",
                  "0x0E01 word 1: drive fault code, 0xFFFF = no fault (table not legible)")
          .named_values(fault_code_labels());
  pts[pt::state_word] =
      input_point("state_word", PointType::u16, "", "0x0E01 word 2: drive state bits")
          .named_bits(state_labels());
  pts[pt::running] = flag("running", "state bit 4: the drive is running", "stopped", "running");
  pts[pt::direction] = flag("direction", "state bit 1: running direction", "forward", "reverse");
  pts[pt::commanded_direction] =
      flag("commanded_direction", "state bit 3: commanded direction", "forward", "reverse");
  pts[pt::accelerating] = flag("accelerating", "state bit 10: accelerating", "no", "yes");
  pts[pt::decelerating] = flag("decelerating", "state bit 11: decelerating", "no", "yes");
  // 0x2001 in 0.01 Hz (specs README: 0x1388 = 50.00 Hz); the 16-bit register tops at 655.35 Hz.
  pts[pt::frequency_setpoint] =
      holding_point("frequency_setpoint", PointType::u16, "Hz",
                    "frequency reference for 0x2001; setpoint_rpm x poles / 120")
          .scaled(0.01)
          .limited(0.0, 655.35);

  for (const MonitorSel& m : s.monitors) {
    const std::string id = "monitor_" + hex4(m.reg, false);
    const std::string reg = "monitor 0x" + hex4(m.reg, true);
    pts.push_back(
        input_point(id, PointType::f32, m.unit, reg + " scaled by its format word").trended());
    pts.push_back(input_point(id + "_raw", PointType::u16, "", reg + " word 1, unscaled"));
    pts.push_back(
        input_point(id + "_format", PointType::u16, "", reg + " word 2: decimals, unit, stopped")
            .named_bits(format_labels()));
  }

  for (const std::uint16_t p : s.parameters) {
    char name[16];
    std::snprintf(name, sizeof name, "param_%02x_%02x", p >> 8, p & 0xFF);
    pts.push_back(
        holding_point(name, PointType::u16, "",
                      "drive parameter at 0x" + hex4(p, true) + ", raw (read 03, written 06)")
            .limited(0, 0xFFFF));
  }
  return pts;
}

}  // namespace drivegate::ed3100
