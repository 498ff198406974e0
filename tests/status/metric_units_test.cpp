// A point's unit as Prometheus names it (status/metric_units.h): the base unit of each known unit,
// the conversions, and the rounding that keeps the digits a drive sent and no others.
#include "status/metric_units.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <vector>

namespace drivegate {
namespace {

double in_base(std::string_view unit, double value) {
  const auto u = metric_unit(unit);
  EXPECT_TRUE(u.has_value()) << unit;
  return u ? round_significant(u->to_base(value), 12) : NAN;
}

std::string_view suffix(std::string_view unit) {
  const auto u = metric_unit(unit);
  return u ? u->unit().suffix : std::string_view("(none)");
}

TEST(MetricUnit, TheAdaptersUnitsHaveTheirBaseUnits) {
  // Every unit an adapter of this tree gives a point (adapters/*/points.cpp) and the profiles'.
  EXPECT_EQ(suffix("degC"), "celsius");
  EXPECT_EQ(suffix("K"), "kelvin");
  EXPECT_EQ(suffix("V"), "volts");
  EXPECT_EQ(suffix("A"), "amperes");
  EXPECT_EQ(suffix("W"), "watts");
  EXPECT_EQ(suffix("Hz"), "hertz");
  EXPECT_EQ(suffix("rpm"), "rpm");
  EXPECT_EQ(suffix("bar"), "pascals");
  EXPECT_EQ(suffix("s"), "seconds");
  EXPECT_EQ(suffix("kg"), "grams");
  EXPECT_EQ(suffix("%"), "ratio");
  EXPECT_EQ(suffix("Nm"), "newton_meters");
}

TEST(MetricUnit, ConvertsToTheBaseUnit) {
  EXPECT_EQ(in_base("degC", 23.4), 23.4);
  EXPECT_EQ(in_base("K", 5.5), 5.5);  // a difference (superheat) or absolute: never shifted
  EXPECT_EQ(in_base("degF", 212), 100);
  EXPECT_EQ(in_base("degF", 32), 0);
  EXPECT_EQ(in_base("\xc2\xb0"
                    "F",
                    -40),
            -40);
  EXPECT_EQ(in_base("kW", 1.25), 1250);
  EXPECT_EQ(in_base("bar", 2.35), 235000);  // not 235000.00000000003
  EXPECT_EQ(in_base("mbar", 1013.25), 101325);
  EXPECT_EQ(in_base("psi", 1), 6894.75729317);  // 12 significant digits
  EXPECT_EQ(in_base("%", 45), 0.45);
  EXPECT_EQ(in_base("ms", 250), 0.25);
  EXPECT_EQ(in_base("min", 2.5), 150);
  EXPECT_EQ(in_base("kg", 4.2), 4200);
  EXPECT_EQ(in_base("mA", 1500), 1.5);
  EXPECT_EQ(in_base("kWh", 2), 7.2e6);
}

TEST(MetricUnit, NoneForNoUnitOrOneItDoesNotKnow) {
  EXPECT_FALSE(metric_unit(""));
  EXPECT_FALSE(metric_unit("l/min"));
  EXPECT_FALSE(metric_unit("MA"));  // case matters: not mA
  EXPECT_FALSE(metric_unit("degc"));
}

TEST(MetricUnit, EveryBaseUnitIsAValidPluralNameSuffixAndEveryUnitIsListedOnce) {
  // https://prometheus.io/docs/concepts/data_model/: [a-zA-Z_:][a-zA-Z0-9_:]*
  const std::regex name("[a-z_]+");
  std::set<std::string_view> suffixes;
  for (const BaseUnit& b : kBaseUnits) {
    EXPECT_TRUE(std::regex_match(std::string(b.suffix), name)) << b.suffix;
    EXPECT_TRUE(suffixes.insert(b.suffix).second) << b.suffix;
    EXPECT_FALSE(b.words.empty()) << b.suffix;
  }
  std::set<std::string_view> units;
  std::set<std::size_t> used;
  for (const KnownUnit& k : kKnownUnits) {
    EXPECT_TRUE(units.insert(k.unit).second) << k.unit;
    ASSERT_LT(k.metric.base, kBaseUnits.size()) << k.unit;
    used.insert(k.metric.base);
    EXPECT_EQ(metric_unit(k.unit)->base, k.metric.base) << k.unit;
  }
  EXPECT_EQ(used.size(), kBaseUnits.size()) << "a base unit no unit converts to";
}

// docs/metrics.md's table lists every unit the code knows, with its base unit on the same row.
TEST(MetricUnit, TheDocumentationListsEveryUnit) {
  std::ifstream in(std::string(DRIVEGATE_SOURCE_DIR) + "/docs/metrics.md");
  ASSERT_TRUE(in) << "docs/metrics.md";
  std::vector<std::string> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with("| `")) rows.push_back(line);
  }
  for (const KnownUnit& k : kKnownUnits) {
    const std::string unit = "`" + std::string(k.unit) + "`";
    const std::string base = "| `" + std::string(k.metric.unit().suffix) + "` |";
    const bool listed = std::any_of(rows.begin(), rows.end(), [&](const std::string& r) {
      return r.find(unit) != std::string::npos && r.find(base) != std::string::npos;
    });
    EXPECT_TRUE(listed) << k.unit << " -> " << k.metric.unit().suffix;
  }
}

TEST(RoundSignificant, KeepsTheDigitsAskedFor) {
  EXPECT_EQ(round_significant(234 * 0.1, 12), 23.4);
  EXPECT_NE(234 * 0.1, 23.4);  // what it is there for
  EXPECT_EQ(round_significant(static_cast<double>(12.3F), 7), 12.3);
  EXPECT_EQ(round_significant(-0.000123456789, 3), -0.000123);
  EXPECT_EQ(round_significant(4294967295.0, 12), 4294967295.0);
  EXPECT_EQ(round_significant(123456789012345678.0, 12), 123456789012345678.0);  // no fraction
  EXPECT_EQ(round_significant(0.0, 12), 0.0);
  EXPECT_TRUE(std::isnan(round_significant(NAN, 12)));
  EXPECT_EQ(round_significant(INFINITY, 12), INFINITY);
  EXPECT_EQ(round_significant(1e-320, 12), 1e-320);  // too small to scale: as it is
}

}  // namespace
}  // namespace drivegate
