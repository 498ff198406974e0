// A point's unit (PointSpec::unit: "degC", "bar", "kW", ...) as Prometheus names it: the base unit
// the metric's name ends in and how the engineering value converts to it. Prometheus asks for
// base units, spelled out in the plural, as the name's suffix, so that every exporter's
// temperatures are in one unit and every one's pressures in another
// (https://prometheus.io/docs/practices/naming/#base-units): degC is `celsius`, kW is `watts`
// (x 1000), bar is `pascals` (x 100000), % is `ratio` (x 0.01), kg is `grams` (x 1000).
//
// One table, here; docs/metrics.md prints it. A unit it does not know (a profile's "l/min") has
// no base unit: such a point is not exported as a number (the status JSON still shows it), rather
// than under a name that says nothing of what it measures.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string_view>

namespace drivegate {

// A base unit: the metric name's suffix, and its words for the HELP line.
struct BaseUnit {
  std::string_view suffix;  // "celsius"
  std::string_view words;   // "degrees Celsius"
};

// In the order /metrics writes their families.
inline constexpr std::array<BaseUnit, 14> kBaseUnits = {{
    {"celsius", "degrees Celsius"},
    // Prometheus prefers celsius "for practical reasons"; kelvin is for what must be absolute or
    // is a difference (a refrigerant's superheat): a point in K stays in kelvin, never shifted.
    {"kelvin", "kelvin"},
    {"volts", "volts"},
    {"amperes", "amperes"},
    {"watts", "watts"},
    {"joules", "joules"},
    {"hertz", "hertz"},
    // No SI base unit for a shaft's speed is in use on drives: drivegate says rpm everywhere
    // (drivegate_device_speed_rpm, the register map), so do the points.
    {"rpm", "revolutions per minute"},
    {"pascals", "pascals"},
    {"seconds", "seconds"},
    {"grams", "grams"},
    {"meters", "meters"},
    {"ratio", "ratio (0..1)"},
    {"newton_meters", "newton metres"},
}};

// How a value in a point's unit becomes one in a base unit: base = value x scale + offset.
struct MetricUnit {
  std::size_t base;  // index into kBaseUnits
  double scale = 1.0;
  double offset = 0.0;
  [[nodiscard]] double to_base(double value) const { return value * scale + offset; }
  [[nodiscard]] const BaseUnit& unit() const { return kBaseUnits.at(base); }
};

// The base unit of `unit` as an adapter or profile writes it (case matters: "mA" is not "MA"); none
// for "" and for a unit the table does not know.
std::optional<MetricUnit> metric_unit(std::string_view unit);

// Every unit the table knows: the adapters' own, and the usual others a profile may carry.
struct KnownUnit {
  std::string_view unit;
  MetricUnit metric;
};
inline constexpr std::array kKnownUnits = {
    KnownUnit{"degC", {0}},
    KnownUnit{"\u00b0C", {0}},  // "°C"
    KnownUnit{"degF", {0, 5.0 / 9.0, -32.0 * 5.0 / 9.0}},
    KnownUnit{"\u00b0F", {0, 5.0 / 9.0, -32.0 * 5.0 / 9.0}},
    KnownUnit{"K", {1}},
    KnownUnit{"V", {2}},
    KnownUnit{"mV", {2, 1e-3}},
    KnownUnit{"kV", {2, 1e3}},
    KnownUnit{"A", {3}},
    KnownUnit{"mA", {3, 1e-3}},
    KnownUnit{"W", {4}},
    KnownUnit{"kW", {4, 1e3}},
    KnownUnit{"J", {5}},
    KnownUnit{"kJ", {5, 1e3}},
    KnownUnit{"Wh", {5, 3600.0}},
    KnownUnit{"kWh", {5, 3.6e6}},
    KnownUnit{"Hz", {6}},
    KnownUnit{"kHz", {6, 1e3}},
    KnownUnit{"rpm", {7}},
    KnownUnit{"Pa", {8}},
    KnownUnit{"hPa", {8, 1e2}},
    KnownUnit{"kPa", {8, 1e3}},
    KnownUnit{"MPa", {8, 1e6}},
    KnownUnit{"mbar", {8, 1e2}},
    KnownUnit{"bar", {8, 1e5}},
    KnownUnit{"psi", {8, 6894.757293168}},  // the pound-force per square inch (NIST SP 811, B.8)
    KnownUnit{"s", {9}},
    KnownUnit{"ms", {9, 1e-3}},
    KnownUnit{"min", {9, 60.0}},
    KnownUnit{"h", {9, 3600.0}},
    KnownUnit{"g", {10}},
    KnownUnit{"kg", {10, 1e3}},
    KnownUnit{"m", {11}},
    KnownUnit{"mm", {11, 1e-3}},
    KnownUnit{"%", {12, 1e-2}},
    KnownUnit{"Nm", {13}},
};

// `value` with at most `digits` significant decimal digits. A drive's value is a register times a
// scale (234 x 0.1) or a float; times a unit's scale it is 23.400000000000002 or
// 235000.00000000003 Pa, digits no drive sent: what the metrics show is rounded to what the
// value had (docs/metrics.md, "Values").
double round_significant(double value, int digits);

}  // namespace drivegate
