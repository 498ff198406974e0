#include "points.h"

#include "codec.h"
#include "program.h"

namespace drivegate::fdc1 {
namespace {

PointSpec input(std::string name, double scale, std::string unit, std::string description,
                std::vector<Label> labels = {}) {
  PointSpec p;
  p.name = std::move(name);
  p.table = Table::input;
  p.scale = scale;
  p.unit = std::move(unit);
  p.description = std::move(description);
  p.labels = std::move(labels);
  return p;
}

PointSpec holding(std::string name, double scale, std::string unit, std::string description,
                  double min, double max) {
  PointSpec p = input(std::move(name), scale, std::move(unit), std::move(description));
  p.table = Table::holding;
  p.min = min;
  p.max = max;
  return p;
}

// Highest voltage a programming word can carry: 65535 / 1187 (INPUT programming).
constexpr double kMaxVolts = 55.0;

PointSpec volts(std::string name, std::string description) {
  return holding(std::move(name), 0.01, "V", std::move(description), 0.0, kMaxVolts);
}

}  // namespace

std::vector<PointSpec> make_points(bool programming) {
  std::vector<PointSpec> p;
  p.push_back(input("motor_on", 1, "", "streamed form: 1 motor ON (speed, current), 0 OFF",
                    {{"off", 0}, {"on", 1}}));
  // OUTPUT: current = INT / 3160 A; 65535 / 3160 = 20.7 A fits u16 in mA.
  p.push_back(input("current_a", 0.001, "A", "measured motor current (0 while the motor is off)"));
  // OUTPUT: time = TR / 122 s; 65535 / 122 = 537 s fits u16 in 0.1 s.
  p.push_back(input("restart_s", 0.1, "s", "seconds until the next motor start (motor off)"));
  p.push_back(input("alarm_code", 1, "", "raw alarm code A of the OFF form (ranges of 16)",
                    {{"none", 0},
                     {"battery out of limits", 16},
                     {"fan output overload", 32},
                     {"motor failed to start", 48},
                     {"motor overload", 64},
                     {"overtemperature", 80},
                     {"fan output overload (end of retries)", 160},
                     {"motor failed to start (end of retries)", 176},
                     {"motor overload (end of retries)", 192},
                     {"overtemperature (end of retries)", 208},
                     {"internal error", 240}}));
  p.push_back(input("alarm_latched", 1, "", "1: the alarm is an (end of retries) one",
                    {{"retrying", 0}, {"end of retries", 1}}));
  p.push_back(input("sent_speed_rpm", 1, "rpm",
                    "slave mode: speed last programmed over the line (0 = stop)"));
  if (!programming) return p;

  p.push_back(holding("prog_min_rpm", 1, "rpm", "programming: minimum speed", kMinRpm, kMaxRpm));
  p.push_back(holding("prog_max_rpm", 1, "rpm", "programming: maximum speed", kMinRpm, kMaxRpm));
  PointSpec mode = holding("prog_mode", 1, "",
                           "programming: mode byte, sum of one member per group "
                           "(128 | 0/16/32 | 0/4/8/12 | 0/2/3)",
                           0, 255);
  mode.labels = {{"slave mode", kModeSlave},
                 {"speed proportional to battery voltage", kModeProportional},
                 {"smart speed", 4},
                 {"sleep mode", 8},
                 {"energy saving sleep mode", 12},
                 {"external battery limits", kModeExternalLimits},
                 {"special battery system", kModeSpecial},
                 {"3 minutes delay", kModeDelay}};
  p.push_back(std::move(mode));
  p.push_back(volts("prog_cut_out_12v", "programming, standard: 12 V system cut-out (> 9 V)"));
  p.push_back(volts("prog_cut_in_12v", "programming, standard: 12 V system cut-in (< 17 V)"));
  p.push_back(volts("prog_cut_out_24v", "programming, standard: 24 V system cut-out (> 17 V)"));
  p.push_back(volts("prog_cut_in_24v", "programming, standard: 24 V system cut-in (< 33 V)"));
  p.push_back(volts("prog_cut_out_42v", "programming, standard: 42 V system cut-out (> 33 V)"));
  p.push_back(volts("prog_cut_in_42v", "programming, standard: 42 V system cut-in (< 46 V)"));
  p.push_back(volts("prog_cut_out_special", "programming, special: cut-out (> 9 V)"));
  p.push_back(volts("prog_cut_in_special", "programming, special: cut-in (< nominal)"));
  p.push_back(volts("prog_nominal_v", "programming, special: nominal voltage (< 46 V)"));
  p.push_back(holding("prog_commit", 1, "",
                      "write 1: validate every prog_* limit and store them in the controller's "
                      "non-volatile memory",
                      1, 1));
  p.push_back(input("prog_status", 1, "", "outcome of the last prog_commit",
                    {{"idle", 0},
                     {"pending", 1},
                     {"ok", 2},
                     {"refused", 3},
                     {"no_response", 4},
                     {"invalid", 5}}));
  PointSpec message = input("prog_message", 1, "", "why the last prog_commit failed");
  message.type = PointType::string;
  message.string_registers = 40;
  p.push_back(std::move(message));
  return p;
}

}  // namespace drivegate::fdc1
