#include "points.h"

#include <string>
#include <utility>

#include "faults.h"

namespace drivegate::nidec {
namespace {

PointSpec holding(std::string name, double scale, std::string unit, std::string description,
                  double min, double max, std::vector<Label> labels = {}) {
  PointSpec p;
  p.name = std::move(name);
  p.table = Table::holding;
  p.scale = scale;
  p.unit = std::move(unit);
  p.description = std::move(description);
  p.labels = std::move(labels);
  p.min = min;
  p.max = max;
  return p;
}

PointSpec input(std::string name, double scale, std::string unit, std::string description,
                std::vector<Label> labels = {}, PointType type = PointType::u16) {
  PointSpec p;
  p.name = std::move(name);
  p.table = Table::input;
  p.type = type;
  p.scale = scale;
  p.unit = std::move(unit);
  p.description = std::move(description);
  p.labels = std::move(labels);
  return p;
}

// 5.5: each agitation time is one byte of 100 ms units: 0 .. 25.5 s.
PointSpec agitation_time(std::string name, std::string what) {
  return holding(std::move(name), 0.1, "s", "agitation " + what + " time (5.5), next run", 0.0,
                 25.5);
}

}  // namespace

std::vector<PointSpec> make_points() {
  std::vector<PointSpec> p;
  p.reserve(pt::count);
  p.push_back(holding("motion", 1, "",
                      "what run_forward/run_reverse start (reverse: rotation only)", 0, 3,
                      {{"rotation", 0}, {"spin", 1}, {"agitation", 2}, {"free_shaft_spin", 3}}));
  // 5.3 / 5.4 / 5.6 / 5.14: 16-bit accel time in 100 ms units.
  p.push_back(
      holding("accel_time", 0.1, "s", "accel time of CW/CCW/spin/free-shaft spin", 0.0, 6553.5));
  p.push_back(agitation_time("agitation_accel", "accel"));
  p.push_back(agitation_time("agitation_decel", "decel"));
  p.push_back(agitation_time("agitation_cw_on", "CW on"));
  p.push_back(agitation_time("agitation_cw_off", "CW off"));
  p.push_back(agitation_time("agitation_ccw_on", "CCW on"));
  p.push_back(agitation_time("agitation_ccw_off", "CCW off"));
  p.push_back(holding("action", 1, "", "one-shot request; reads back the last one written", 0,
                      kActionMax,
                      {{"none", 0},
                       {"voltage_detection", 1},
                       {"weight_detection", 2},
                       {"fabric_detection", 3},
                       {"forced_brake_enable", 4},
                       {"forced_brake_disable", 5},
                       {"fct_test", 6},
                       {"ping", 7}}));
  p.push_back(input("action_status", 1, "", "outcome of the last action",
                    {{"idle", 0}, {"pending", 1}, {"done", 2}, {"no_response", 3}}));
  p.push_back(input("inverter_version", 1, "", "inverter version number from the ping ACK (5.1)"));
  p.push_back(input("platform", 1, "", "washer platform echoed by the ping ACK (5.1)"));
  PointSpec bits = input("error_bits", 1, "", "Error byte of the last ACK (section 8 bitmask)",
                         fault_bit_labels());
  bits.bit_labels = true;
  p.push_back(std::move(bits));
  p.push_back(
      input("weight", 0.1, "kg", "load weight, 100 g units (5.2 / 5.10), 0 = not detected"));
  p.push_back(input("raw_weight", 1, "", "raw weight data from weight detection (5.10)"));
  p.push_back(input("dc_bus_voltage", 1, "V", "DC bus voltage from voltage detection (5.9)"));
  p.push_back(input("forced_brake", 1, "", "forced brake state from its ACK (5.13)",
                    {{"disabled", 0}, {"enabled", 1}}));
  p.push_back(input("fabric_raw", 1, "", "fabric detection ACK bytes 3..6 raw, big-endian (5.11)",
                    {}, PointType::u32));
  p.push_back(input("fct_error", 1, "", "FCT ACK error, 16 bits (5.15)"));
  p.push_back(input("fct_speed_rpm", 1, "rpm", "FCT ACK actual motor speed (5.15)"));
  p.push_back(input("fct_ipm_temperature", 1, "", "FCT ACK IPM temperature, raw (5.15)"));
  p.push_back(input("fct_ipm_model_bus_volt_high", 1, "",
                    "FCT ACK byte 9: IPM model + bus volt high byte, raw (5.15)"));
  p.push_back(input("fct_bus_volt_low", 1, "", "FCT ACK byte 10: bus volt low byte, raw (5.15)"));
  p.push_back(input("fct_phase_current", 1, "", "FCT ACK phase current, raw (5.15)"));
  return p;
}

}  // namespace drivegate::nidec
