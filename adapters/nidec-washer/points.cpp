#include "points.h"

#include <string>
#include <utility>

#include "faults.h"

namespace drivegate::nidec {
namespace {

// 5.5: each agitation time is one byte of 100 ms units: 0 .. 25.5 s.
PointSpec agitation_time(std::string name, const std::string& what) {
  return holding_point(std::move(name), PointType::u16, "s",
                       "agitation " + what + " time (5.5), used by the next agitation")
      .scaled(0.1)
      .limited(0.0, 25.5);
}

PointSpec raw(std::string name, std::string description) {
  return input_point(std::move(name), PointType::u16, "", std::move(description));
}

}  // namespace

std::vector<PointSpec> make_points() {
  std::vector<PointSpec> p;
  p.reserve(pt::count);
  p.push_back(holding_point("motion", PointType::u16, "",
                            "what run_forward/run_reverse start (reverse: rotation only)")
                  .limited(0.0, static_cast<double>(kMotionNames.size() - 1))
                  .named_values(labels_in_order(kMotionNames)));
  // 5.3 / 5.4 / 5.6 / 5.14: 16-bit accel time in 100 ms units.
  p.push_back(holding_point("accel_time", PointType::u16, "s",
                            "accel time of CW/CCW/spin/free-shaft spin, used by the next run")
                  .scaled(0.1)
                  .limited(0.0, 6553.5));
  p.push_back(agitation_time("agitation_accel", "accel"));
  p.push_back(agitation_time("agitation_decel", "decel"));
  p.push_back(agitation_time("agitation_cw_on", "CW on"));
  p.push_back(agitation_time("agitation_cw_off", "CW off"));
  p.push_back(agitation_time("agitation_ccw_on", "CCW on"));
  p.push_back(agitation_time("agitation_ccw_off", "CCW off"));
  p.push_back(holding_point("action", PointType::u16, "",
                            "one-shot request; reads back the last one written")
                  .limited(0.0, static_cast<double>(kActionNames.size() - 1))
                  .named_values(labels_in_order(kActionNames)));
  p.push_back(raw("action_status", "outcome of the last action")
                  .named_values(labels_in_order(kActionStatusNames)));
  p.push_back(raw("inverter_version", "inverter version number from the ping ACK (5.1)"));
  p.push_back(raw("platform", "washer platform echoed by the ping ACK (5.1)"));
  p.push_back(raw("error_bits", "Error byte of the last ACK (section 8 bitmask)")
                  .named_bits(fault_bit_labels()));
  p.push_back(input_point("weight", PointType::u16, "kg",
                          "load weight, 100 g units (5.2 / 5.10), 0 = not detected")
                  .scaled(0.1));
  p.push_back(raw("raw_weight", "raw weight data from weight detection (5.10)"));
  p.push_back(input_point("dc_bus_voltage", PointType::u16, "V",
                          "DC bus voltage from voltage detection (5.9)")
                  .trended());
  p.push_back(raw("forced_brake", "forced brake state from its ACK (5.13)")
                  .named_values({{"disabled", 0}, {"enabled", 1}}));
  p.push_back(input_point("fabric_raw", PointType::u32, "",
                          "fabric detection ACK bytes 3..6 raw, big-endian (5.11)"));
  p.push_back(raw("fct_error", "FCT ACK error, 16 bits (5.15)"));
  p.push_back(
      input_point("fct_speed_rpm", PointType::u16, "rpm", "FCT ACK actual motor speed (5.15)"));
  p.push_back(raw("fct_ipm_temperature", "FCT ACK IPM temperature, raw (5.15)"));
  p.push_back(raw("fct_ipm_model_bus_volt_high",
                  "FCT ACK byte 9: IPM model + bus volt high byte, raw (5.15)"));
  p.push_back(raw("fct_bus_volt_low", "FCT ACK byte 10: bus volt low byte, raw (5.15)"));
  p.push_back(raw("fct_phase_current", "FCT ACK phase current, raw (5.15)"));
  return p;
}

}  // namespace drivegate::nidec
