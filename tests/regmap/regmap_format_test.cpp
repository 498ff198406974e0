// The printed register map in its three forms.
#include "regmap/regmap_format.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace drivegate {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

std::vector<DeviceRegisters> one_device(const DeviceConfig& cfg) {
  PointSpec f{.name = "suction_pressure",
              .table = Table::input,
              .type = PointType::f32,
              .unit = "bar",
              .description = "suction \"P\""};
  return {{&cfg, RegisterMap({f})}};
}

const std::vector<ServedOn> kListeners = {{"0.0.0.0:502", WordOrder::big},
                                          {"127.0.0.1:1503", WordOrder::little}};

// The options a device runs with, a profile's own among them, each as its JSON type.
TEST(RegmapFormat, JsonSaysTheDevicesOptions) {
  DeviceConfig cfg{.name = "fan", .adapter = "modbus", .unit_id = 2};
  cfg.options.set("profile", std::string("abb-acs580"));
  cfg.options.set("motor_poles", 2.0);
  cfg.options.set("attempts", std::int64_t{3});
  cfg.options.set("passthrough", false);
  const auto json = format_regmap(one_device(cfg), kListeners, RegmapFormat::json);
  EXPECT_THAT(json, HasSubstr("\"adapter\": \"modbus\", \"options\": {\"attempts\": 3, "
                              "\"motor_poles\": 2, \"passthrough\": false, \"profile\": "
                              "\"abb-acs580\"}, \"points\": ["));
}

TEST(RegmapFormat, JsonHasEveryFieldOfTheSchema) {
  DeviceConfig cfg{.name = "c1", .adapter = "unicla-edrive", .unit_id = 4};
  const auto json = format_regmap(one_device(cfg), kListeners, RegmapFormat::json);
  EXPECT_THAT(json, HasSubstr("{\"devices\": ["));
  EXPECT_THAT(json, HasSubstr("{\"unit_id\": 4, \"name\": \"c1\", \"adapter\": \"unicla-edrive\""));
  EXPECT_THAT(json, HasSubstr("{\"name\": \"suction_pressure\", \"table\": \"input\", "
                              "\"address\": 32, \"reference\": \"30033\", \"type\": \"f32\", "
                              "\"scale\": 1, \"unit\": \"bar\", \"access\": \"read\", "
                              "\"description\": \"suction \\\"P\\\"\""));
  EXPECT_THAT(json, HasSubstr("\"name\": \"command\", \"table\": \"holding\", \"address\": 0, "
                              "\"reference\": \"40001\""));
  EXPECT_THAT(json, HasSubstr("\"run_forward\": 1"));
  EXPECT_THAT(json, HasSubstr("\"stall\": 7"));
  EXPECT_THAT(json, HasSubstr("\"listeners\": [\n  {\"address\": \"0.0.0.0:502\", \"word_order\": "
                              "\"big\"},\n  {\"address\": \"127.0.0.1:1503\", \"word_order\": "
                              "\"little\"}\n]}"));
}

TEST(RegmapFormat, CsvAndMarkdown) {
  DeviceConfig cfg{.name = "c1", .adapter = "x", .unit_id = 4};
  const auto csv = format_regmap(one_device(cfg), kListeners, RegmapFormat::csv);
  EXPECT_THAT(csv, HasSubstr("unit_id,device,adapter,name,table,address,reference,type,"));
  EXPECT_THAT(csv, HasSubstr("4,c1,x,suction_pressure,input,32,30033,f32,2,1,bar,read,"
                             "\"suction \"\"P\"\"\","));
  const auto md = format_regmap(one_device(cfg), kListeners, RegmapFormat::markdown);
  EXPECT_THAT(md, HasSubstr("## Unit 4: c1 (x)"));
  EXPECT_THAT(md, HasSubstr("| input | 32 | 30033 | suction_pressure | f32 |"));
}

// Modicon references: 0xxxx coils, 1xxxx discrete inputs, 3xxxx input registers, 4xxxx holding
// registers, each 1 + the address.
TEST(RegmapFormat, ModiconReferences) {
  EXPECT_EQ(modicon_reference(Table::coil, 0, 5), "00001");
  EXPECT_EQ(modicon_reference(Table::discrete, 6, 5), "10007");
  EXPECT_EQ(modicon_reference(Table::input, 6, 5), "30007");
  EXPECT_EQ(modicon_reference(Table::holding, 9998, 5), "49999");
  EXPECT_EQ(modicon_reference(Table::holding, 9999, 6), "410000");
  EXPECT_EQ(modicon_reference(Table::coil, 65535, 6), "065536");
}

// Tables in reference order (coils, discrete inputs, input, holding), each in address order; the
// bit tables typed as bits.
TEST(RegmapFormat, TablesInReferenceOrderAndBitsAsBits) {
  DeviceConfig cfg{.name = "d", .adapter = "x", .unit_id = 1};
  std::vector<PointSpec> points = {
      {.name = "h_point", .table = Table::holding, .type = PointType::u16},
      {.name = "a_coil", .table = Table::coil, .type = PointType::u16},
      {.name = "a_discrete", .table = Table::discrete, .type = PointType::u16},
  };
  const std::vector<DeviceRegisters> devices = {{&cfg, RegisterMap(points)}};
  const auto md = format_regmap(devices, kListeners, RegmapFormat::markdown);
  const auto coil = md.find("| coil | 0 | 00001 | a_coil | bit |");
  const auto status_bit = md.find("| discrete | 0 | 10001 | status_online | bit |");
  const auto discrete = md.find("| discrete | 16 | 10017 | a_discrete | bit |");
  const auto input = md.find("| input | 0 | 30001 | status | u16 |");
  const auto last_input = md.find("| input | 29 | 30030 | foreign_frames | u32 |");
  const auto holding = md.find("| holding | 0 | 40001 | command | u16 |");
  const auto adapter_holding = md.find("| holding | 16 | 40017 | h_point | u16 |");
  ASSERT_NE(coil, std::string::npos) << md;
  ASSERT_NE(status_bit, std::string::npos) << md;
  ASSERT_NE(discrete, std::string::npos) << md;
  ASSERT_NE(input, std::string::npos) << md;
  ASSERT_NE(last_input, std::string::npos) << md;
  ASSERT_NE(holding, std::string::npos) << md;
  ASSERT_NE(adapter_holding, std::string::npos) << md;
  EXPECT_LT(coil, status_bit);
  EXPECT_LT(status_bit, discrete);
  EXPECT_LT(discrete, input);
  EXPECT_LT(input, last_input);
  EXPECT_LT(last_input, holding);
  EXPECT_LT(holding, adapter_holding);
  EXPECT_THAT(md, Not(HasSubstr("| discrete | 1 | 10002 | status_running | u16")));
  const auto json = format_regmap(devices, kListeners, RegmapFormat::json);
  EXPECT_THAT(json, HasSubstr("\"name\": \"status_online\", \"table\": \"discrete\", "
                              "\"address\": 0, \"reference\": \"10001\", \"type\": \"bit\""));
  EXPECT_LT(json.find("\"a_coil\""), json.find("\"status_online\""));
  EXPECT_LT(json.find("\"status_online\""), json.find("\"status\""));
}

// Five digits name addresses up to 9998 (x9999); one register past it, in any point, makes every
// reference of the printout six digits long. A long string point reaches there.
TEST(RegmapFormat, SixDigitReferencesPastAddress9998) {
  DeviceConfig cfg{.name = "d", .adapter = "x", .unit_id = 1};
  const auto text = [&](std::uint16_t registers) {
    // Holding adapter points start at 16: the string's last register is 15 + `registers`.
    PointSpec s{.name = "text", .table = Table::holding, .type = PointType::string};
    s.string_registers = registers;
    const std::vector<DeviceRegisters> devices = {{&cfg, RegisterMap({s})}};
    return format_regmap(devices, kListeners, RegmapFormat::markdown);
  };
  const auto up_to_9998 = text(9983);
  EXPECT_THAT(up_to_9998, HasSubstr("| holding | 16 | 40017 | text |"));
  EXPECT_THAT(up_to_9998, HasSubstr("| discrete | 0 | 10001 | status_online |"));
  const auto to_9999 = text(9984);
  EXPECT_THAT(to_9999, HasSubstr("| holding | 16 | 400017 | text |"));
  EXPECT_THAT(to_9999, HasSubstr("| holding | 0 | 400001 | command |"));
  EXPECT_THAT(to_9999, HasSubstr("| discrete | 0 | 100001 | status_online |"));
  EXPECT_THAT(to_9999, HasSubstr("input registers 300001 + address"));
}

// The access column names the level a client needs to write the point, as the listeners'
// `access` does: the command block and a point its adapter opened to operate are operate's, any
// other writable point maintain's, and a point nobody writes is read.
TEST(RegmapFormat, AccessSaysWhichLevelMayWriteEachPoint) {
  DeviceConfig cfg{.name = "d", .adapter = "x", .unit_id = 1};
  PointSpec open_to_operate{
      .name = "reset_counter", .table = Table::holding, .type = PointType::u16};
  open_to_operate.write_level = PointSpec::WriteLevel::operate;
  PointSpec closed{.name = "serial_no", .table = Table::holding, .type = PointType::u16};
  closed.write_level = PointSpec::WriteLevel::none;
  const std::vector<DeviceRegisters> devices = {
      {&cfg, RegisterMap({{.name = "accel", .table = Table::holding, .type = PointType::u16},
                          open_to_operate,
                          closed,
                          {.name = "dc_volts", .table = Table::input, .type = PointType::u16}})}};
  const auto md = format_regmap(devices, kListeners, RegmapFormat::markdown);
  for (const char* row : {"| holding | 0 | 40001 | command | u16 | 1 |  | operate |",
                          "| holding | 1 | 40002 | setpoint_rpm | i16 | 1 | rpm | operate |",
                          "| holding | 2 | 40003 | heartbeat | u16 | 1 |  | operate |",
                          "| holding | 16 | 40017 | accel | u16 | 1 |  | maintain |",
                          "| holding | 17 | 40018 | reset_counter | u16 | 1 |  | operate |",
                          "| holding | 18 | 40019 | serial_no | u16 | 1 |  | read |",
                          "| input | 32 | 30033 | dc_volts | u16 | 1 |  | read |",
                          "| input | 0 | 30001 | status | u16 | 1 |  | read |"}) {
    EXPECT_THAT(md, HasSubstr(row));
  }
  EXPECT_THAT(md, Not(HasSubstr("| rw |")));
  EXPECT_THAT(md, HasSubstr("Access is the level a listener"));
  const auto csv = format_regmap(devices, kListeners, RegmapFormat::csv);
  EXPECT_THAT(csv, HasSubstr("1,d,x,accel,holding,16,40017,u16,1,1,,maintain,"));
  EXPECT_THAT(csv, HasSubstr("1,d,x,command,holding,0,40001,u16,1,1,,operate,"));
  const auto json = format_regmap(devices, kListeners, RegmapFormat::json);
  EXPECT_THAT(json, HasSubstr("\"name\": \"reset_counter\", \"table\": \"holding\", \"address\": "
                              "17, \"reference\": \"40018\", \"type\": \"u16\", \"scale\": 1, "
                              "\"unit\": \"\", \"access\": \"operate\""));
  EXPECT_THAT(json, HasSubstr("\"name\": \"serial_no\", \"table\": \"holding\", \"address\": 18, "
                              "\"reference\": \"40019\", \"type\": \"u16\", \"scale\": 1, "
                              "\"unit\": \"\", \"access\": \"read\""));
}

TEST(RegmapFormat, MarkdownSaysEachListenersWordOrder) {
  DeviceConfig cfg{.name = "c1", .adapter = "x", .unit_id = 4};
  const auto md = format_regmap(one_device(cfg), kListeners, RegmapFormat::markdown);
  EXPECT_THAT(md, HasSubstr("- 0.0.0.0:502: big: high word first (mbpoll -B)\n"));
  EXPECT_THAT(md, HasSubstr("- 127.0.0.1:1503: little: low word first (mbpoll without -B)\n"));
  const auto unsaid = format_regmap(one_device(cfg), {}, RegmapFormat::markdown);
  EXPECT_THAT(unsaid, HasSubstr("Word order of 32-bit values and floats: big, high word first"));
}

}  // namespace
}  // namespace drivegate
