#include "points.h"

#include "codec.h"
#include "faults.h"
#include "program.h"

namespace drivegate::fdc1 {
namespace {

// Highest voltage a programming word can carry: 65535 / 1187 = 55.2 V (INPUT programming).
constexpr double kMaxVolts = 55.0;

PointSpec rpm_field(std::string name, std::string description) {
  return holding_point(std::move(name), PointType::u16, "rpm", std::move(description))
      .limited(kMinRpm, kMaxRpm);
}

// Volts in 0.01 V registers: 55 V is 5500, well inside a u16.
PointSpec volts_field(std::string name, std::string description) {
  return holding_point(std::move(name), PointType::u16, "V", std::move(description))
      .scaled(0.01)
      .limited(0.0, kMaxVolts);
}

}  // namespace

std::vector<PointSpec> make_points(bool programming) {
  std::vector<PointSpec> v(programming ? pt::count : pt::prog_min_rpm);
  v[pt::motor_on] = input_point("motor_on", PointType::u16, "",
                                "streamed form: 1 motor ON (speed, current), 0 OFF")
                        .named_values({{"off", 0}, {"on", 1}});
  // OUTPUT: current = INT / 3160 A; 65535 / 3160 = 20.7 A fits a u16 in mA.
  v[pt::current_a] = input_point("current_a", PointType::u16, "A",
                                 "measured motor current (0 while the motor is off)")
                         .scaled(0.001)
                         .trended();
  // OUTPUT: time = TR / 122 s; 65535 / 122 = 537 s fits a u16 in 0.1 s.
  v[pt::restart_s] = input_point("restart_s", PointType::u16, "s",
                                 "seconds until the next motor start (motor off)")
                         .scaled(0.1);
  v[pt::alarm_code] = input_point("alarm_code", PointType::u16, "",
                                  "raw alarm code A of the OFF form (ranges of 16)")
                          .named_values(alarm_labels());
  v[pt::alarm_latched] =
      input_point("alarm_latched", PointType::u16, "", "1: the alarm is an (end of retries) one")
          .named_values({{"retrying", 0}, {"end of retries", 1}});
  v[pt::sent_speed_rpm] = input_point("sent_speed_rpm", PointType::u16, "rpm",
                                      "slave mode: speed last programmed over the line (0 = stop)");
  if (!programming) return v;

  v[pt::prog_min_rpm] = rpm_field("prog_min_rpm", "programming: minimum speed");
  v[pt::prog_max_rpm] = rpm_field("prog_max_rpm", "programming: maximum speed");
  v[pt::prog_mode] =
      holding_point("prog_mode", PointType::u16, "",
                    "programming: mode byte, sum of one member per group "
                    "(128 | 0/16/32 | 0/4/8/12 | 0/2/3)")
          .limited(0, 255)
          .named_values({{"slave mode", kModeSlave},
                         {"speed proportional to battery voltage", kModeProportional},
                         {"smart speed", kModeSmartSpeed},
                         {"sleep mode", kModeSleep},
                         {"energy saving sleep mode", kModeEnergySaving},
                         {"external battery limits", kModeExternalLimits},
                         {"special battery system", kModeSpecial},
                         {"3 minutes delay", kModeDelay}});
  v[pt::prog_cut_out_12v] =
      volts_field("prog_cut_out_12v", "programming, standard: 12 V system cut-out (> 9 V)");
  v[pt::prog_cut_in_12v] =
      volts_field("prog_cut_in_12v", "programming, standard: 12 V system cut-in (< 17 V)");
  v[pt::prog_cut_out_24v] =
      volts_field("prog_cut_out_24v", "programming, standard: 24 V system cut-out (> 17 V)");
  v[pt::prog_cut_in_24v] =
      volts_field("prog_cut_in_24v", "programming, standard: 24 V system cut-in (< 33 V)");
  v[pt::prog_cut_out_42v] =
      volts_field("prog_cut_out_42v", "programming, standard: 42 V system cut-out (> 33 V)");
  v[pt::prog_cut_in_42v] =
      volts_field("prog_cut_in_42v", "programming, standard: 42 V system cut-in (< 46 V)");
  v[pt::prog_cut_out_special] =
      volts_field("prog_cut_out_special", "programming, special: cut-out (> 9 V)");
  v[pt::prog_cut_in_special] =
      volts_field("prog_cut_in_special", "programming, special: cut-in (< nominal)");
  v[pt::prog_nominal_v] =
      volts_field("prog_nominal_v", "programming, special: nominal voltage (< 46 V)");
  v[pt::prog_commit] = holding_point(kCommitPoint, PointType::u16, "",
                                     "write 1: validate every prog_* limit and store them in the "
                                     "controller's non-volatile memory")
                           .limited(1, 1);
  v[pt::prog_status] =
      input_point("prog_status", PointType::u16, "",
                  "programming: pending, the last commit's outcome, or whether one may go")
          .named_values(labels_in_order(kProgStatusNames));
  v[pt::prog_message] = string_point(
      kMessagePoint, 40, "why a prog_commit now would be refused, or why the last one failed");
  return v;
}

}  // namespace drivegate::fdc1
