// The printed register map in its three forms.
#include "format/regmap_format.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace drivegate {
namespace {

using ::testing::HasSubstr;

std::vector<DeviceRegisters> one_device(const DeviceConfig& cfg) {
  PointSpec f{.name = "suction_pressure",
              .table = Table::input,
              .type = PointType::f32,
              .unit = "bar",
              .description = "suction \"P\""};
  return {{&cfg, RegisterMap({f})}};
}

TEST(RegmapFormat, JsonHasEveryFieldOfTheSchema) {
  DeviceConfig cfg{.name = "c1", .adapter = "unicla-edrive", .unit_id = 4};
  const auto json = format_regmap(one_device(cfg), RegmapFormat::json);
  EXPECT_THAT(json, HasSubstr("{\"devices\": ["));
  EXPECT_THAT(json, HasSubstr("{\"unit_id\": 4, \"name\": \"c1\", \"adapter\": \"unicla-edrive\""));
  EXPECT_THAT(json,
              HasSubstr("{\"name\": \"suction_pressure\", \"table\": \"input\", "
                        "\"address\": 32, \"type\": \"f32\", \"scale\": 1, \"unit\": "
                        "\"bar\", \"access\": \"r\", \"description\": \"suction \\\"P\\\"\""));
  EXPECT_THAT(json, HasSubstr("\"name\": \"command\", \"table\": \"holding\", \"address\": 0"));
  EXPECT_THAT(json, HasSubstr("\"run_forward\": 1"));
  EXPECT_THAT(json, HasSubstr("\"stall\": 7"));
}

TEST(RegmapFormat, CsvAndMarkdown) {
  DeviceConfig cfg{.name = "c1", .adapter = "x", .unit_id = 4};
  const auto csv = format_regmap(one_device(cfg), RegmapFormat::csv);
  EXPECT_THAT(csv,
              HasSubstr("4,c1,x,suction_pressure,input,32,f32,2,1,bar,r,\"suction \"\"P\"\"\","));
  const auto md = format_regmap(one_device(cfg), RegmapFormat::markdown);
  EXPECT_THAT(md, HasSubstr("## Unit 4: c1 (x)"));
  EXPECT_THAT(md, HasSubstr("| input | 32 | suction_pressure | f32 |"));
}

}  // namespace
}  // namespace drivegate
