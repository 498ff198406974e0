// /metrics as a Prometheus user reads it (docs/metrics.md), rendered from a gateway of two fake
// drives whose adapter has a point of each kind: measurements named by their base unit and
// converted to it, named values and bit fields as state sets, the common block's enumerations as
// state sets, the writes by source and result, the event history, the process's own; and
// promtool finding nothing to lint in it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "fake_adapter.h"
#include "gateway/device.h"
#include "gateway/gateway.h"
#include "modbus/server.h"
#include "net/clock.h"
#include "plugin/adapter_options.h"
#include "status/status_view.h"

namespace drivegate {
namespace {

using ::testing::AllOf;
using ::testing::Contains;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;

// A drive with one point of each kind the metrics tell apart; its values are fixed, the second
// drive's temperature one degree above the first's.
std::unique_ptr<Driver> make_meter(const DeviceEnv& env, std::string&) {
  auto d = std::make_unique<test::FakeDriver>(env);
  d->points_ = {
      input_point("temperature", PointType::i16, "degC", "").scaled(0.1),
      input_point("suction_pressure", PointType::f32, "bar", ""),
      input_point("power", PointType::u16, "kW", "").scaled(0.01),
      input_point("demand", PointType::u16, "%", ""),
      input_point("frequency", PointType::u16, "Hz", "").scaled(0.01),
      input_point("current", PointType::u16, "A", "").scaled(0.001),
      input_point("superheat", PointType::f32, "K", ""),
      input_point("flow", PointType::u16, "l/min", ""),  // a unit without a base unit
      input_point("raw_code", PointType::u16, "", ""),   // a number without a unit
      input_point("op_state", PointType::u16, "", "")
          // Two codes named alike (a vendor's table): one state.
          .named_values({{"stopped", 0}, {"running", 1}, {"tripped", 2}, {"running", 3}}),
      input_point("safety", PointType::u16, "", "")
          .named_bits({{"overcurrent", 0}, {"overvoltage", 1}, {"door \"open\"", 4}}),
      string_point("serial", 2, ""),
      holding_point("limit", PointType::u16, "rpm", "").limited(0, 3000),
      string_point("drive_name", 8, ""),
      string_point("long_text", 40, ""),
  };
  d->values_ = {20.0 + env.address + 0.4,  // 21.4, 22.4
                3.5, 1.25, std::int64_t{45}, 50.0, 1.5, 5.5, std::int64_t{7}, std::int64_t{9},
                std::int64_t{3},        // running (the second of its codes)
                std::int64_t{0b10001},  // overcurrent, door "open"
                std::string("AB12"), std::int64_t{1200},
                // Quotes, a backslash, a line feed and two bytes beyond ASCII (UTF-8's e-acute).
                std::string("say \"hi\" \\\n\xC3\xA9!"), std::string(80, 'x')};
  d->common_.ready = true;
  d->common_.running = true;
  d->common_.speed_rpm = 1480;
  d->common_.setpoint_rpm = 1500;
  d->common_.command = Command::run_forward;
  d->common_.faults.set(Fault::over_current);
  d->common_.faults.set(Fault::stall);
  d->common_.native_fault = 0x0E01;
  return d;
}

AdapterDescriptor meter_adapter() {
  AdapterDescriptor a = test::kFakeAdapter;
  a.id = "meter";
  a.create_driver = make_meter;
  return a;
}

class NoBackend final : public modbus::Backend {
 public:
  modbus::Exception read(const Session&, std::uint8_t, Table, std::uint16_t,
                         std::span<std::uint16_t>) override {
    return modbus::Exception::gateway_path_unavailable;
  }
  modbus::Exception write(const Session&, std::uint8_t, Table, std::uint16_t,
                          std::span<const std::uint16_t>, modbus::WriteDone) override {
    return modbus::Exception::gateway_path_unavailable;
  }
};

modbus::ServerOptions loopback() {
  modbus::ServerOptions o;
  o.listeners.front().host = "127.0.0.1";
  o.listeners.front().port = 0;
  return o;
}

class MetricsText : public ::testing::Test {
 protected:
  MetricsText() {
    plugins_.add(descriptor_);
    Config config;
    config.path = "drivegate.toml";
    BusConfig bus;
    bus.name = "line-a";
    bus.port = "/nonexistent/tty-a";  // never opened: the values are the drivers' own
    bus.baud = 4800;
    config.buses.push_back(bus);
    for (const std::uint8_t unit : {std::uint8_t{1}, std::uint8_t{2}}) {
      DeviceConfig d;
      d.name = "meter-" + std::to_string(unit);
      d.bus = "line-a";
      d.adapter = "meter";
      d.unit_id = unit;
      d.address = unit;
      d.options = default_options(descriptor_);
      config.devices.push_back(d);
    }
    std::vector<std::string> errors;
    gateway_ = Gateway::build(io_, config, plugins_, log_, errors);
    EXPECT_TRUE(errors.empty()) << errors.front();
    for (const auto& d : gateway_->devices()) d->link().health.frame_good(Clock::now());
    EXPECT_FALSE(server_.listen());

    counts_.n[static_cast<std::size_t>(SourceKind::modbus)][0] = 7;
    counts_.n[static_cast<std::size_t>(SourceKind::mqtt)]
             [static_cast<std::size_t>(Outcome::no_such_device)] = 2;
    counts_.n[static_cast<std::size_t>(SourceKind::failsafe)][0] = 1;
    counts_.folded_n[static_cast<std::size_t>(SourceKind::modbus)][0] = 4;
    for (int i = 0; i < 5; ++i) {
      history_.add(Event{.kind = EventKind::reload, .message = "reloaded " + std::to_string(i)});
    }
  }

  StatusView view(bool with_history = true) {
    StatusView v{.gateway = *gateway_, .server = server_, .version = "9.8.7", .started_unix = 1e9};
    if (with_history) {
      v.commands = &counts_;
      v.history = &history_;
    }
    // A serial listener with a quote in its port's name, as label values must survive.
    SerialListenerView s{.port = "/dev/ttyS\"1",
                         .framing = "rtu",
                         .access = AccessLevel::operate,
                         .open = true,
                         .bytes_received = 800,
                         .reopens = 2};
    s.counters.bus_messages = 100;
    s.counters.bus_comm_errors = 3;
    s.counters.bus_exception_errors = 4;
    s.counters.server_messages = 90;
    s.counters.server_no_response = 5;
    s.counters.bus_char_overruns = 1;
    s.counters.broken_frames = 6;
    s.counters.other_units = 7;
    s.counters.broadcasts = 2;
    s.counters.broadcasts_refused = 2;
    v.serial.push_back(s);
    return v;
  }

  const AdapterDescriptor descriptor_ = meter_adapter();
  PluginRegistry plugins_;
  // Before io_, so it outlives it: destroying the io_context destroys the handlers that still
  // hold the server's acceptor, whose timer detaches from the clock as it goes.
  net::SteadyClock clock_;
  boost::asio::io_context io_;
  std::shared_ptr<spdlog::logger> log_ =
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::unique_ptr<Gateway> gateway_;
  NoBackend backend_;
  modbus::Server server_{io_, clock_, backend_, loopback(), log_};
  CommandCounts counts_;
  EventLog history_{3, [] { return std::int64_t{1'700'000'000'000}; }};  // 5 added: 2 dropped
};

// The lines of family `name`: its HELP and TYPE, then its samples, as the document has them.
std::vector<std::string> family(const std::string& text, const std::string& name) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const bool ours = line.starts_with("# HELP " + name + " ") ||
                      line.starts_with("# TYPE " + name + " ") || line.starts_with(name + "{") ||
                      line.starts_with(name + " ");
    if (ours) out.push_back(line);
  }
  return out;
}

// Every line of family `name` that names `point` (its samples of that point).
std::vector<std::string> of_point(const std::string& text, const std::string& name,
                                  const std::string& point) {
  std::vector<std::string> out;
  for (auto& l : family(text, name)) {
    if (l.find("point=\"" + point + "\"") != std::string::npos) out.push_back(l);
  }
  return out;
}

constexpr const char* kOne = R"(device="meter-1",adapter="meter",unit="1",bus="line-a")";
constexpr const char* kTwo = R"(device="meter-2",adapter="meter",unit="2",bus="line-a")";
std::string labels(const char* device, const std::string& more) {
  return std::string("{") + device + more + "}";
}

TEST_F(MetricsText, AdapterMeasurementsAreNamedByTheirBaseUnitAndConvertedToIt) {
  const std::string text = metrics_text(view());
  // Both drives' points of one base unit are one family, written together.
  EXPECT_THAT(
      family(text, "drivegate_device_point_celsius"),
      ElementsAre(
          "# HELP drivegate_device_point_celsius adapter points measured in "
          "degrees Celsius, converted from the point's unit (docs/metrics.md)",
          "# TYPE drivegate_device_point_celsius gauge",
          "drivegate_device_point_celsius" + labels(kOne, R"(,point="temperature")") + " 21.4",
          "drivegate_device_point_celsius" + labels(kTwo, R"(,point="temperature")") + " 22.4"));
  const auto one = [&](const std::string& name, const std::string& point) {
    auto lines = of_point(text, name, point);
    return lines.empty() ? std::string("(none)") : lines.front();
  };
  EXPECT_EQ(one("drivegate_device_point_pascals", "suction_pressure"),
            "drivegate_device_point_pascals" + labels(kOne, R"(,point="suction_pressure")") +
                " 350000");  // 3.5 bar
  EXPECT_EQ(one("drivegate_device_point_watts", "power"),
            "drivegate_device_point_watts" + labels(kOne, R"(,point="power")") + " 1250");
  EXPECT_EQ(one("drivegate_device_point_ratio", "demand"),
            "drivegate_device_point_ratio" + labels(kOne, R"(,point="demand")") + " 0.45");
  EXPECT_EQ(one("drivegate_device_point_hertz", "frequency"),
            "drivegate_device_point_hertz" + labels(kOne, R"(,point="frequency")") + " 50");
  EXPECT_EQ(one("drivegate_device_point_amperes", "current"),
            "drivegate_device_point_amperes" + labels(kOne, R"(,point="current")") + " 1.5");
  EXPECT_EQ(one("drivegate_device_point_kelvin", "superheat"),
            "drivegate_device_point_kelvin" + labels(kOne, R"(,point="superheat")") + " 5.5");
  EXPECT_EQ(one("drivegate_device_point_rpm", "limit"),
            "drivegate_device_point_rpm" + labels(kOne, R"(,point="limit")") + " 1200");
  // No base unit, no unit: not numbers of the metrics.
  for (const char* point : {"flow", "raw_code"}) {
    EXPECT_THAT(text, Not(HasSubstr("point=\"" + std::string(point) + "\""))) << point;
  }
}

// A string point is an info gauge, its text a label: printable ASCII, the format's escapes, other
// bytes '?', at most 64 characters; the status JSON carries the whole text, escaped.
TEST_F(MetricsText, StringPointsAreInfoGaugesAndJsonStrings) {
  const std::string text = metrics_text(view());
  const std::string info = "drivegate_device_point_info";
  EXPECT_THAT(of_point(text, info, "serial"),
              ElementsAre(info + labels(kOne, R"(,point="serial",value="AB12")") + " 1",
                          info + labels(kTwo, R"(,point="serial",value="AB12")") + " 1"));
  EXPECT_THAT(
      of_point(text, info, "drive_name"),
      Contains(info + labels(kOne, R"(,point="drive_name",value="say \"hi\" \\\n??!")") + " 1"));
  EXPECT_THAT(
      of_point(text, info, "long_text"),
      Contains(info +
               labels(kOne, ",point=\"long_text\",value=\"" + std::string(64, 'x') + "...\"") +
               " 1"));
  EXPECT_THAT(family(text, info), Contains("# TYPE " + info + " gauge"));
  const std::string json = status_json(view());
  EXPECT_THAT(json, HasSubstr(R"({"name": "serial", "value": "AB12", "unit": ""})"));
  EXPECT_THAT(json,
              HasSubstr(R"({"name": "drive_name", "value": "say \"hi\" \\\n??!", "unit": ""})"));
  EXPECT_THAT(json, HasSubstr("{\"name\": \"long_text\", \"value\": \"" + std::string(80, 'x') +
                              "\", \"unit\": \"\"}"));
}

TEST_F(MetricsText, NamedValuesAndBitFieldsAreStateSets) {
  const std::string text = metrics_text(view());
  const std::string state = "drivegate_device_point_state";
  EXPECT_THAT(family(text, state),
              ElementsAre("# HELP " + state +
                              " adapter points with named values: 1 for the name of the value "
                              "in force",
                          "# TYPE " + state + " gauge",
                          state + labels(kOne, R"(,point="op_state",state="stopped")") + " 0",
                          state + labels(kOne, R"(,point="op_state",state="running")") + " 1",
                          state + labels(kOne, R"(,point="op_state",state="tripped")") + " 0",
                          state + labels(kTwo, R"(,point="op_state",state="stopped")") + " 0",
                          state + labels(kTwo, R"(,point="op_state",state="running")") + " 1",
                          state + labels(kTwo, R"(,point="op_state",state="tripped")") + " 0"));
  const std::string flag = "drivegate_device_point_flag";
  EXPECT_THAT(of_point(text, flag, "safety"),
              ElementsAre(flag + labels(kOne, R"(,point="safety",flag="overcurrent")") + " 1",
                          flag + labels(kOne, R"(,point="safety",flag="overvoltage")") + " 0",
                          flag + labels(kOne, R"(,point="safety",flag="door \"open\"")") + " 1",
                          flag + labels(kTwo, R"(,point="safety",flag="overcurrent")") + " 1",
                          flag + labels(kTwo, R"(,point="safety",flag="overvoltage")") + " 0",
                          flag + labels(kTwo, R"(,point="safety",flag="door \"open\"")") + " 1"));
}

TEST_F(MetricsText, TheCommonBlocksEnumerationsAreStateSets) {
  const std::string text = metrics_text(view());
  const auto samples = [&](const std::string& name) {
    auto lines = family(text, name);
    lines.erase(std::remove_if(lines.begin(), lines.end(),
                               [&](const std::string& l) {
                                 return l.starts_with('#') || l.find(kOne) == std::string::npos;
                               }),
                lines.end());
    return lines;
  };
  const std::string cmd = "drivegate_device_command";
  EXPECT_THAT(samples(cmd), ElementsAre(cmd + labels(kOne, R"(,command="stop")") + " 0",
                                        cmd + labels(kOne, R"(,command="run_forward")") + " 1",
                                        cmd + labels(kOne, R"(,command="run_reverse")") + " 0",
                                        cmd + labels(kOne, R"(,command="quick_stop")") + " 0",
                                        cmd + labels(kOne, R"(,command="reset_fault")") + " 0"));
  EXPECT_THAT(family(text, cmd), Contains("# TYPE " + cmd + " gauge"));
  // The most severe active fault: one state of the unified vocabulary's 18 is 1.
  const std::string code = "drivegate_device_fault_code";
  const auto codes = samples(code);
  EXPECT_EQ(codes.size(), kFaultNames.size());
  EXPECT_THAT(codes, Contains(code + labels(kOne, R"(,fault="none")") + " 0"));
  EXPECT_THAT(codes, Contains(code + labels(kOne, R"(,fault="over_current")") + " 1"));
  EXPECT_EQ(std::count_if(codes.begin(), codes.end(), [](auto& l) { return l.ends_with(" 1"); }),
            1);
  // Every active fault: 1 for each; `none` is no bit of the mask.
  const std::string mask = "drivegate_device_fault_mask";
  const auto masks = samples(mask);
  EXPECT_EQ(masks.size(), kFaultNames.size() - 1);
  EXPECT_THAT(masks, Not(Contains(HasSubstr("fault=\"none\""))));
  EXPECT_THAT(masks, Contains(mask + labels(kOne, R"(,fault="over_current")") + " 1"));
  EXPECT_THAT(masks, Contains(mask + labels(kOne, R"(,fault="stall")") + " 1"));
  EXPECT_EQ(std::count_if(masks.begin(), masks.end(), [](auto& l) { return l.ends_with(" 1"); }),
            2);
  // The status register's bits.
  const std::string status = "drivegate_device_status";
  EXPECT_THAT(samples(status),
              ElementsAre(status + labels(kOne, R"(,status="online")") + " 1",
                          status + labels(kOne, R"(,status="running")") + " 1",
                          status + labels(kOne, R"(,status="fault")") + " 1",
                          status + labels(kOne, R"(,status="warning")") + " 0",
                          status + labels(kOne, R"(,status="comm_lost")") + " 0",
                          status + labels(kOne, R"(,status="failsafe")") + " 0",
                          status + labels(kOne, R"(,status="command_pending")") + " 0"));
  // The drive's own code: a label, in hex as the status page shows it.
  EXPECT_THAT(samples("drivegate_device_native_fault_info"),
              ElementsAre("drivegate_device_native_fault_info" +
                          labels(kOne, R"(,native_fault="0x0E01")") + " 1"));
  // The numbers stay numbers.
  EXPECT_THAT(samples("drivegate_device_speed_rpm"),
              ElementsAre("drivegate_device_speed_rpm" + labels(kOne, "") + " 1480"));
  EXPECT_THAT(samples("drivegate_device_setpoint_rpm"),
              ElementsAre("drivegate_device_setpoint_rpm" + labels(kOne, "") + " 1500"));
  // No code is left a bare number to graph.
  for (const char* bare : {"drivegate_device_native_fault{", "drivegate_device_native_fault "}) {
    EXPECT_THAT(text, Not(HasSubstr(bare)));
  }
  for (const auto& l : family(text, code)) {
    if (!l.starts_with('#')) {
      EXPECT_THAT(l, HasSubstr(",fault=\""));
    }
  }
}

TEST_F(MetricsText, WritesBySourceAndResultEveryPair) {
  const std::string text = metrics_text(view());
  const auto lines = family(text, "drivegate_writes_total");
  ASSERT_EQ(lines.size(), 2 + kSourceKindNames.size() * kOutcomeNames.size());
  EXPECT_EQ(lines[0],
            "# HELP drivegate_writes_total writes to the drives, from any northbound or the "
            "gateway itself, by source and result");
  EXPECT_EQ(lines[1], "# TYPE drivegate_writes_total counter");
  EXPECT_EQ(lines[2], R"(drivegate_writes_total{source="modbus",result="ok"} 7)");
  EXPECT_THAT(lines,
              Contains(R"(drivegate_writes_total{source="mqtt",result="no_such_device"} 2)"));
  EXPECT_THAT(lines, Contains(R"(drivegate_writes_total{source="failsafe",result="ok"} 1)"));
  EXPECT_THAT(lines,
              Contains(R"(drivegate_writes_total{source="gateway",result="no_response"} 0)"));
  for (const auto& l : lines) EXPECT_THAT(l, Not(HasSubstr("result=\"no such")));
  // Of those, the writes folded into a summary record (docs/audit.md), likewise every pair.
  const auto folded = family(text, "drivegate_audit_folded_total");
  ASSERT_EQ(folded.size(), 2 + kSourceKindNames.size() * kOutcomeNames.size());
  EXPECT_EQ(folded[1], "# TYPE drivegate_audit_folded_total counter");
  EXPECT_EQ(folded[2], R"(drivegate_audit_folded_total{source="modbus",result="ok"} 4)");
  EXPECT_THAT(folded, Contains(R"(drivegate_audit_folded_total{source="mqtt",result="denied"} 0)"));
}

TEST_F(MetricsText, TheEventHistory) {
  const std::string text = metrics_text(view());
  EXPECT_THAT(family(text, "drivegate_history_events"),
              ElementsAre("# HELP drivegate_history_events entries the event history holds now",
                          "# TYPE drivegate_history_events gauge", "drivegate_history_events 3"));
  EXPECT_THAT(family(text, "drivegate_history_dropped_total"),
              ElementsAre("# HELP drivegate_history_dropped_total history entries pushed out, "
                          "oldest first, to make room for newer ones",
                          "# TYPE drivegate_history_dropped_total counter",
                          "drivegate_history_dropped_total 2"));
  EXPECT_THAT(family(text, "drivegate_history_bytes"),
              Contains("drivegate_history_bytes " + std::to_string(history_.memory_bytes())));
  EXPECT_GT(history_.memory_bytes(), 0u);
  // Each shelf: what it holds, keeps at most, and let go (the reloads are the plant's events).
  EXPECT_THAT(family(text, "drivegate_history_shelf_entries"),
              ElementsAre("# HELP drivegate_history_shelf_entries entries each shelf of the event "
                          "history holds now",
                          "# TYPE drivegate_history_shelf_entries gauge",
                          R"(drivegate_history_shelf_entries{shelf="events"} 3)",
                          R"(drivegate_history_shelf_entries{shelf="commands"} 0)",
                          R"(drivegate_history_shelf_entries{shelf="refusals"} 0)"));
  EXPECT_THAT(family(text, "drivegate_history_shelf_capacity"),
              Contains(R"(drivegate_history_shelf_capacity{shelf="refusals"} 3)"));
  EXPECT_THAT(family(text, "drivegate_history_shelf_dropped_total"),
              Contains(R"(drivegate_history_shelf_dropped_total{shelf="events"} 2)"));
}

TEST_F(MetricsText, NoWritesNorHistoryInADocumentRenderedWithout) {
  const std::string text = metrics_text(view(false));
  EXPECT_THAT(text, Not(HasSubstr("drivegate_writes_total")));
  EXPECT_THAT(text, Not(HasSubstr("drivegate_history_")));
  EXPECT_THAT(text, HasSubstr("drivegate_device_point_celsius{"));
}

TEST_F(MetricsText, TheStandardProcessMetrics) {
  const std::string text = metrics_text(view());
  for (const auto& [name, type] :
       std::map<std::string, std::string>{{"process_cpu_seconds_total", "counter"},
                                          {"process_resident_memory_bytes", "gauge"},
                                          {"process_virtual_memory_bytes", "gauge"},
                                          {"process_open_fds", "gauge"},
                                          {"process_max_fds", "gauge"},
                                          {"process_start_time_seconds", "gauge"}}) {
    const auto lines = family(text, name);
    ASSERT_EQ(lines.size(), 3u) << name;
    EXPECT_EQ(lines[1], "# TYPE " + name + " " + type);
    const double v = std::strtod(lines[2].c_str() + name.size() + 1, nullptr);
    // A test's process may not have used a clock tick of CPU yet.
    EXPECT_GE(v, name == "process_cpu_seconds_total" ? 0 : 1) << lines[2];
  }
  // The kernel's start time of this process, not the view's.
  const auto start = family(text, "process_start_time_seconds");
  EXPECT_NE(start[2], "process_start_time_seconds 1000000000");
}

// Each family's HELP and TYPE once, its samples right after them, no series twice: what
// Prometheus needs to take the scrape at all.
// Each serial listener's counters, by port; the status JSON's serial_listeners entry.
TEST_F(MetricsText, SerialListenersCountersByPort) {
  const std::string text = metrics_text(view());
  const std::string port = R"({port="/dev/ttyS\"1"})";
  EXPECT_THAT(family(text, "drivegate_serial_listener_open"),
              ElementsAre(HasSubstr("# HELP"), "# TYPE drivegate_serial_listener_open gauge",
                          "drivegate_serial_listener_open" + port + " 1"));
  EXPECT_THAT(family(text, "drivegate_serial_listener_frames_total"),
              Contains("drivegate_serial_listener_frames_total" + port + " 100"));
  EXPECT_THAT(family(text, "drivegate_serial_listener_crc_errors_total"),
              Contains("drivegate_serial_listener_crc_errors_total" + port + " 3"));
  EXPECT_THAT(family(text, "drivegate_serial_listener_not_answered_total"),
              Contains("drivegate_serial_listener_not_answered_total" + port + " 5"));
  EXPECT_THAT(family(text, "drivegate_serial_listener_broadcasts_refused_total"),
              Contains("drivegate_serial_listener_broadcasts_refused_total" + port + " 2"));
  EXPECT_THAT(family(text, "drivegate_serial_listener_reopens_total"),
              Contains("drivegate_serial_listener_reopens_total" + port + " 2"));
  const std::string json = status_json(view());
  EXPECT_THAT(json,
              HasSubstr(R"({"port": "/dev/ttyS\"1", "framing": "rtu", "access": "operate", )"
                        R"("open": true, "reopens": 2, "bytes_received": 800, "frames": 100, )"
                        R"("crc_errors": 3, "exceptions": 4, "requests": 90, )"
                        R"("not_answered": 5, "busy": 0, "overruns": 1, "broken_frames": 6, )"
                        R"("other_units": 7, "broadcasts": 2, "broadcasts_refused": 2, )"
                        R"("accepted_then_failed": 0})"));
  // None without a serial listener.
  StatusView plain = view();
  plain.serial.clear();
  EXPECT_THAT(metrics_text(plain), Not(HasSubstr("drivegate_serial_listener")));
  EXPECT_THAT(status_json(plain), HasSubstr("\"serial_listeners\": []"));
}

TEST_F(MetricsText, EveryFamilyOnceWithItsSamplesTogetherAndNoSeriesTwice) {
  const std::string text = metrics_text(view());
  std::set<std::string> families;
  std::set<std::string> series;
  std::string current;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.starts_with("# HELP ")) {
      current = line.substr(7, line.find(' ', 7) - 7);
      EXPECT_TRUE(families.insert(current).second) << "family twice: " << current;
      continue;
    }
    if (line.starts_with("# TYPE ")) {
      EXPECT_TRUE(line.starts_with("# TYPE " + current + " ")) << line;
      continue;
    }
    const auto name = line.substr(0, line.find_first_of("{ "));
    EXPECT_EQ(name, current) << "sample outside its family: " << line;
    EXPECT_TRUE(series.insert(line.substr(0, line.rfind(' '))).second) << "twice: " << line;
  }
  EXPECT_GT(families.size(), 60u);
}

// promtool (Debian's prometheus, tools/deps.sh test) on the whole document, state sets, escaped
// label values and all.
TEST_F(MetricsText, PromtoolFindsNothingToLint) {
  if (std::system("command -v promtool > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "promtool is not installed (tools/deps.sh test installs prometheus)";
  }
  const auto dir =
      std::filesystem::temp_directory_path() / ("drivegate-metrics-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "metrics.txt") << metrics_text(view());
  const std::string cmd = "promtool check metrics < '" + (dir / "metrics.txt").string() + "' > '" +
                          (dir / "promtool.out").string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  std::ostringstream out;
  out << std::ifstream(dir / "promtool.out").rdbuf();
  std::filesystem::remove_all(dir);
  EXPECT_EQ(status, 0) << out.str();
  EXPECT_EQ(out.str(), "");
}

}  // namespace
}  // namespace drivegate
