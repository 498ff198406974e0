// A profile's 64-bit, string and labelled points end to end: the real daemon polls `drivegate sim
// modbus` serving a profile of every byte order, through FC 03 and FC 04, and a PLC reads over
// Modbus TCP the device's exact bits; the register map, the JSON and /metrics show the labels;
// a float's NaN bound to speed_rpm reads unknown with sensor_fault.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "e2e.h"
#include "http_get.h"
#include "mosquitto.h"
#include "mqtt_e2e.h"
#include "sparkplug_peer.h"

namespace drivegate::test::modbus_types_e2e_test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

// Input registers (FC 04) and holding registers (FC 03) of each width and order. In the unified
// map the adapter's inputs start at 32 (energy 32-35, total_s 36-39, state_word 40, ratio 41-42;
// speed is served as the common block's speed_rpm only), its holdings at 16 (serial 16-19, mode
// 20, counter 21-22).
constexpr const char* kProfile = R"([profile]
name = "types-e2e"
source = "this test"
[[point]]
name = "energy"
table = "input"
address = 0
type = "u64"
byte_order = "dcba"
[[point]]
name = "total_s"
table = "input"
address = 4
type = "s64"
byte_order = "badc"
[[point]]
name = "state_word"
table = "input"
address = 8
type = "u16"
bits = { 0 = "ready", 3 = "fault", 15 = "warning" }
[[point]]
name = "speed"
table = "input"
address = 9
type = "f64"
byte_order = "cdab"
[[point]]
name = "ratio"
table = "input"
address = 13
type = "f32"
byte_order = "dcba"
[[point]]
name = "serial"
table = "holding"
address = 20
type = "string"
registers = 4
[[point]]
name = "mode"
table = "holding"
address = 24
type = "u16"
values = { 0 = "off", 2 = "auto", "0x11" = "remote" }
[[point]]
name = "counter"
table = "holding"
address = 25
type = "u32"
byte_order = "badc"
[common]
speed_rpm = "speed"
)";

std::string config(const std::string& port, const std::string& profile, int http_port) {
  return "[[bus]]\nname = \"line-a\"\nport = \"" + port +
         "\"\nbaud = 19200\nparity = \"even\"\n\n"
         "[[device]]\nname = \"meter\"\nbus = \"line-a\"\nadapter = \"modbus\"\nunit_id = 1\n"
         "address = 1\npoll_ms = 100\n[device.options]\nprofile = \"" +
         profile + "\"\n\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) + "\"\n";
}

// A program's stdout and stderr, run to its end.
std::string run_to_end(std::vector<std::string> argv) {
  argv.insert(argv.begin(), {"/bin/sh", "-c", "exec \"$0\" \"$@\" 2>&1"});
  Child child(argv);
  std::string out;
  while (auto line = child.read_line(std::chrono::seconds(20))) out += *line + "\n";
  child.stop(0);
  return out;
}

bool ok(const std::string& answer) {
  return answer.rfind("ok", 0) == 0;
}

using W = std::vector<std::uint16_t>;

TEST(ModbusTypesE2E, APlcReadsTheDevicesExactBitsAndEverySurfaceShowsTheLabels) {
  TempDir dir;
  const auto profile = dir / "types-e2e.toml";
  std::ofstream(profile) << kProfile;
  Sim sim("modbus", dir / "tty-a", {"--set", "profile=" + profile.string(), "--address", "1"});
  // 0x1122334455667788 in dcba: 88 77 66 55 44 33 22 11.
  ASSERT_TRUE(ok(sim.control("raw input 0 0x8877 0x6655 0x4433 0x2211")));
  // -2 as s64 in badc: FF FF FF FF FF FF FE FF.
  ASSERT_TRUE(ok(sim.control("raw input 4 0xFFFF 0xFFFF 0xFFFF 0xFEFF")));
  ASSERT_TRUE(ok(sim.control("raw input 8 0x8009")));  // ready, fault, warning
  ASSERT_TRUE(ok(sim.control("set speed 1234.5")));
  ASSERT_TRUE(ok(sim.control("set ratio 12.5")));
  ASSERT_TRUE(ok(sim.control("set serial AB-12 X")));
  ASSERT_TRUE(ok(sim.control("set mode 17")));
  ASSERT_TRUE(ok(sim.control("set counter 287454020")));  // 0x11223344
  const int http_port = free_port();
  Daemon daemon(dir, config((dir / "tty-a").string(), profile.string(), http_port), {},
                dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  const auto status = [&] { return plc.input(reg::status, 1).regs.at(0); };
  ASSERT_TRUE(eventually([&] { return (status() & reg::online) != 0; }, 10s))
      << slurp(dir / "drivegated.log");

  // Served most significant register first, high byte first, whatever the device's order.
  EXPECT_EQ(plc.input(32, 11).regs, (W{0x1122, 0x3344, 0x5566, 0x7788,  // energy
                                       0xFFFF, 0xFFFF, 0xFFFF, 0xFFFE,  // total_s = -2
                                       0x8009,                          // state_word
                                       0x4148, 0x0000}));               // ratio 12.5 (f32)
  EXPECT_EQ(static_cast<std::int16_t>(plc.input(reg::speed, 1).regs.at(0)), 1235);
  // "AB-12 X" = 41 42 2D 31 32 20 58, NUL-padded; mode 0x11; the counter 0x11223344.
  EXPECT_EQ(plc.holding(16, 7).regs, (W{0x4142, 0x2D31, 0x3220, 0x5800, 0x0011, 0x1122, 0x3344}));

  // Below 2^63 the JSON gives the exact integer.
  EXPECT_THAT(http_get(http_port, "/api/v1/status").body,
              HasSubstr("{\"name\": \"energy\", \"value\": 1234605616436508552,"));

  // Beyond 2^63 the registers still carry the device's bits (a double would make the low ones
  // 0): FF FF FF FF FF FF FF FE in dcba is 0xFEFFFFFFFFFFFFFF.
  ASSERT_TRUE(ok(sim.control("raw input 0 0xFFFF 0xFFFF 0xFFFF 0xFFFE")));
  EXPECT_TRUE(eventually(
      [&] {
        return plc.input(32, 4).regs == W{0xFEFF, 0xFFFF, 0xFFFF, 0xFFFF};
      },
      5s))
      << ::testing::PrintToString(plc.input(32, 4).regs);

  // The register map, the JSON and /metrics name the bits and the value.
  const auto regmap = run_to_end({(bin_dir() / "drivegate").string(), "regmap", "-f", "md", "-c",
                                  daemon.config().string(), "-p", plugin_dir().string()});
  EXPECT_THAT(regmap, HasSubstr("energy"));
  EXPECT_THAT(regmap, HasSubstr("u64"));
  EXPECT_THAT(regmap, HasSubstr("bit 0=ready; bit 3=fault; bit 15=warning"));
  EXPECT_THAT(regmap, HasSubstr("0=off; 2=auto; 17=remote"));
  const std::string json = http_get(http_port, "/api/v1/status").body;
  EXPECT_THAT(json, HasSubstr("{\"name\": \"mode\", \"value\": 17, \"unit\": \"\", \"label\": "
                              "\"remote\"}"));
  // The nearest double, as the JSON prints every double (6 significant digits).
  EXPECT_THAT(json, HasSubstr("{\"name\": \"energy\", \"value\": 1.83747e+19,"));
  EXPECT_THAT(json, HasSubstr("{\"name\": \"total_s\", \"value\": -2,"));
  const std::string map_json = http_get(http_port, "/api/v1/regmap").body;
  EXPECT_THAT(map_json, HasSubstr("\"labels\": {\"ready\": 0, \"fault\": 3, \"warning\": 15}, "
                                  "\"labels_are_bits\": true"));
  const std::string metrics = http_get(http_port, "/metrics").body;
  EXPECT_THAT(metrics, HasSubstr("point=\"state_word\",flag=\"fault\"} 1"));
  EXPECT_THAT(metrics, HasSubstr("point=\"mode\",state=\"remote\"} 1"));
  EXPECT_THAT(metrics, HasSubstr("point=\"mode\",state=\"off\"} 0"));

  // A NaN in the f64 bound to speed_rpm: unknown (-32768) and sensor_fault.
  ASSERT_TRUE(ok(sim.control("raw input 9 0 0 0 0x7FF8")));  // cdab of 7F F8 00...
  EXPECT_TRUE(eventually(
      [&] { return static_cast<std::int16_t>(plc.input(reg::speed, 1).regs.at(0)) == -32768; },
      5s));
  EXPECT_NE(status() & reg::fault, 0);
  EXPECT_EQ(plc.input(reg::fault_code, 1).regs.at(0), 11);  // sensor_fault
  EXPECT_EQ(daemon.stop(), 0);
}

// A string point where the native adapters' points go: the status JSON (a JSON string, escaped),
// /metrics (an info gauge, its text a label) and the Sparkplug DBIRTH and DDATA (a String metric,
// decoded by Eclipse Tahu's decoder), while a PLC reads the string's registers in the device block.
TEST(ModbusTypesE2E, AStringPointReachesTheJsonMetricsAndSparkplug) {
  if (const auto why = missing_dependency()) GTEST_SKIP() << *why;
  TempDir dir;
  const auto profile = dir / "types-e2e.toml";
  std::ofstream(profile) << kProfile;
  Sim sim("modbus", dir / "tty-a", {"--set", "profile=" + profile.string(), "--address", "1"});
  // '"', 'A', '\', a line feed, UTF-8's e-acute (C3 A9), ' ', '!', ' ': the slave's bytes.
  ASSERT_TRUE(ok(sim.control("raw holding 20 0x2241 0x5C0A 0xC3A9 0x2021")));
  Broker broker(dir);
  SparkplugPeer::Options po;
  po.stderr_file = dir / "peer.log";
  SparkplugPeer peer(broker.port(), po);
  const int http_port = free_port();
  Daemon daemon(dir,
                config((dir / "tty-a").string(), profile.string(), http_port) +
                    "\n[mqtt]\nbroker = \"" + broker.url() + "\"\ngroup_id = \"" + kGroup +
                    "\"\nedge_node_id = \"" + kEdge + "\"\n",
                {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(
      eventually([&] { return (plc.input(reg::status, 1).regs.at(0) & reg::online) != 0; }, 10s))
      << slurp(dir / "drivegated.log");
  // The text the adapter reads: the bytes that are no printable ASCII as '?', the trailing space
  // dropped; the PLC reads it NUL-padded, two characters a register (holding 16-19).
  const std::string shown = "\"A\\??? !";
  EXPECT_EQ(plc.holding(16, 4).regs, (W{0x2241, 0x5C3F, 0x3F3F, 0x2021}));
  EXPECT_THAT(http_get(http_port, "/api/v1/status").body,
              HasSubstr(R"({"name": "serial", "value": "\"A\\??? !", "unit": ""})"));
  EXPECT_THAT(http_get(http_port, "/metrics").body,
              HasSubstr(R"(drivegate_device_point_info{device="meter",adapter="modbus",unit="1",)"
                        R"(bus="line-a",point="serial",value="\"A\\??? !"} 1)"));
  const auto birth = peer.wait_for_type("DBIRTH", 10s, "meter");
  ASSERT_TRUE(birth) << describe(peer.history());
  ASSERT_NE(birth->metric("serial"), nullptr) << describe(*birth);
  EXPECT_EQ(birth->metric("serial")->type, "String");
  if (birth->metric("serial")->value != shown) {
    // Born before the first read of it: the text follows in a DDATA.
    EXPECT_TRUE(peer.wait_for(
        [&](const Message& m) {
          const Metric* serial = m.metric("serial");
          return m.message_type() == "DDATA" && serial != nullptr && serial->value == shown;
        },
        10s))
        << describe(peer.history());
  }
  // A new text goes out in a DDATA.
  ASSERT_TRUE(ok(sim.control("set serial SN-0042")));
  const auto data = peer.wait_for(
      [](const Message& m) {
        const Metric* serial = m.metric("serial");
        return m.message_type() == "DDATA" && serial != nullptr && serial->value == "SN-0042";
      },
      10s);
  ASSERT_TRUE(data) << describe(peer.history());
  EXPECT_EQ(data->metric("serial")->type, "String");
  EXPECT_EQ(plc.holding(16, 4).regs, (W{0x534E, 0x2D30, 0x3034, 0x3200}));
  EXPECT_EQ(daemon.stop(), 0);
}
}  // namespace
}  // namespace drivegate::test::modbus_types_e2e_test
