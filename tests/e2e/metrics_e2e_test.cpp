// /metrics end to end: drivegated with [http] on two simulated test drives (the test plugin,
// tests/support/test_adapter), its Prometheus text checked by Debian's promtool (tools/deps.sh
// installs `prometheus`) and scraped by a real Prometheus server on loopback, whose query API
// must agree with what a PLC reads over Modbus.
// Then on every built adapter's simulator at once (as the demo runs them): promtool on their
// points, units and state sets; Prometheus reading a temperature the simulated drive reports,
// the command in force and the writes counted; and the Grafana dashboard the package ships
// (packaging/grafana/drivegate.json) querying only metrics and labels this daemon exports
// (tools/check_grafana.py).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <tuple>

#include "e2e.h"
#include "e2e_adapters.h"
#include "http_get.h"

namespace drivegate::test::metrics_e2e_test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

std::string slurp(const fs::path& file) {
  std::ostringstream text;
  text << std::ifstream(file).rdbuf();
  return text.str();
}

// Two drives, each on its own simulated line: "drive-a" (unit 1) and "drive-b" (unit 2).
std::string config(const fs::path& a, const fs::path& b, int http_port) {
  std::string toml;
  int unit = 1;
  for (const auto& [name, port] : {std::pair{"drive-a", a}, std::pair{"drive-b", b}}) {
    toml += "[[bus]]\nname = \"line-" + std::string(name) + "\"\nport = \"" + port.string() +
            "\"\n\n[[device]]\nname = \"" + name + "\"\nbus = \"line-" + name +
            "\"\nadapter = \"test-drive\"\nunit_id = " + std::to_string(unit++) +
            "\npoll_ms = 100\n\n";
  }
  return toml + "[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) + "\"\n";
}

std::string url_encode(const std::string& s) {
  std::string out;
  for (const unsigned char c : s) {
    if (std::isalnum(c) != 0 || c == '_' || c == '-' || c == '.') {
      out += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

// The one value of an instant query's answer (`"value":[<time>,"<v>"]`), or nullopt when the
// query failed or matched no series / several.
std::optional<double> instant_value(const std::string& json) {
  if (json.find("\"status\":\"success\"") == std::string::npos) return std::nullopt;
  const std::string key = "\"value\":[";
  const auto at = json.find(key);
  if (at == std::string::npos || json.find(key, at + 1) != std::string::npos) return std::nullopt;
  const auto quote = json.find('"', json.find(',', at));
  if (quote == std::string::npos) return std::nullopt;
  return std::strtod(json.c_str() + quote + 1, nullptr);
}

// A Prometheus server on loopback scraping drivegated's /metrics every second.
class Prometheus {
 public:
  Prometheus(const fs::path& dir, int target_port)
      : port_(free_port()), child_(argv(dir, target_port, port_), dir / "prometheus.log") {}
  std::string query(const std::string& promql) {
    return http_get(port_, "/api/v1/query?query=" + url_encode(promql)).body;
  }
  std::optional<double> value(const std::string& promql) { return instant_value(query(promql)); }
  // Waits for the first scrape of the target.
  bool scraping() {
    return eventually([&] { return value("up{job=\"drivegate\"}").value_or(0) == 1; }, 10s);
  }
  [[nodiscard]] int port() const { return port_; }
  int stop() { return child_.stop(SIGTERM, 10s); }

 private:
  static std::vector<std::string> argv(const fs::path& dir, int target_port, int port) {
    std::ofstream(dir / "prometheus.yml")
        << "global:\n  scrape_interval: 1s\n  scrape_timeout: 1s\n  evaluation_interval: 1s\n"
           "scrape_configs:\n  - job_name: drivegate\n    static_configs:\n"
           "      - targets: ['127.0.0.1:"
        << target_port << "']\n";
    fs::create_directories(dir / "tsdb");
    return {"/usr/bin/prometheus", "--config.file=" + (dir / "prometheus.yml").string(),
            "--storage.tsdb.path=" + (dir / "tsdb").string(),
            "--web.listen-address=127.0.0.1:" + std::to_string(port)};
  }
  int port_;
  Child child_;
};

// promtool's complaints about `text` ("" if none); fails the test if it cannot run.
std::string promtool_complaints(const fs::path& dir, const std::string& text) {
  std::ofstream(dir / "metrics.txt") << text;
  const std::string cmd = "promtool check metrics < '" + (dir / "metrics.txt").string() + "' > '" +
                          (dir / "promtool.out").string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string out = slurp(dir / "promtool.out");
  EXPECT_TRUE(WIFEXITED(status)) << out;
  EXPECT_NE(WEXITSTATUS(status), 127) << "promtool not found: tools/deps.sh installs prometheus";
  EXPECT_EQ(WEXITSTATUS(status), 0) << out << "\n--- /metrics:\n" << text;
  return out;
}

class MetricsE2E : public ::testing::Test {
 protected:
  MetricsE2E()
      : http_port_(free_port()),
        sim_a_("test-drive", dir_ / "drive-a"),
        sim_b_("test-drive", dir_ / "drive-b"),
        daemon_(dir_, config(dir_ / "drive-a", dir_ / "drive-b", http_port_), {},
                dir_ / "drivegated.log") {}
  void SetUp() override {
    ASSERT_TRUE(plc_.connect());
    for (const int unit : {1, 2}) {
      plc_.unit(unit);
      ASSERT_TRUE(eventually(
          [&] {
            const auto r = plc_.input(reg::status, 1);
            return r.ok() && (r.regs[0] & reg::online) != 0;
          },
          10s))
          << "unit " << unit << " never online:\n"
          << slurp(dir_ / "drivegated.log");
    }
    ASSERT_TRUE(eventually([&] { return http_get(http_port_, "/metrics").status == 200; }, 5s))
        << slurp(dir_ / "drivegated.log");
  }
  // Runs unit `unit` with `command` at `rpm` and waits until the PLC reads a steady speed;
  // returns it (signed, as the register is i16).
  int run(int unit, std::uint16_t command, std::uint16_t rpm) {
    plc_.unit(unit);
    EXPECT_EQ(plc_.write(reg::command, {command, rpm}), 0);
    int speed = 0;
    EXPECT_TRUE(eventually(
        [&] {
          const auto r = plc_.input(reg::speed, 1);
          if (!r.ok()) return false;
          speed = static_cast<std::int16_t>(r.regs[0]);
          return speed == rpm || speed == -rpm;
        },
        10s))
        << "unit " << unit << " speed " << speed;
    return speed;
  }
  int plc_speed(int unit) {
    plc_.unit(unit);
    return static_cast<std::int16_t>(plc_.input(reg::speed, 1).regs.at(0));
  }

  TempDir dir_;
  int http_port_;
  Sim sim_a_;
  Sim sim_b_;
  Daemon daemon_;
  Plc plc_{daemon_.port()};
};

TEST_F(MetricsE2E, PromtoolFindsNothingToLint) {
  run(1, 1 /*run_forward*/, 800);
  // A Modbus exception, so that the by-code families have samples too.
  plc_.unit(1);
  EXPECT_NE(plc_.write(reg::command, {9}), 0);
  const HttpReply r = http_get(http_port_, "/metrics");
  ASSERT_EQ(r.status, 200);
  EXPECT_THAT(r.headers, HasSubstr("Content-Type: text/plain; version=0.0.4; charset=utf-8"));
  EXPECT_THAT(r.body, HasSubstr("drivegate_device_speed_rpm{device=\"drive-a\""));
  EXPECT_THAT(r.body, HasSubstr("drivegate_device_speed_rpm{device=\"drive-b\""));
  EXPECT_EQ(promtool_complaints(dir_.path(), r.body), "") << "promtool lint complaints";
}

TEST_F(MetricsE2E, PrometheusScrapesWhatThePlcReads) {
  const int a = run(1, 1 /*run_forward*/, 800);
  const int b = run(2, 2 /*run_reverse*/, 600);
  EXPECT_EQ(a, 800);

  Prometheus prometheus(dir_.path(), http_port_);
  const auto query = [&](const std::string& promql) { return prometheus.query(promql); };
  ASSERT_TRUE(prometheus.scraping()) << query("up") << "\n" << slurp(dir_ / "prometheus.log");

  // The scrape went through the whole exposition without an error.
  const std::string targets = http_get(prometheus.port(), "/api/v1/targets").body;
  EXPECT_THAT(targets, HasSubstr("\"health\":\"up\"")) << targets;
  EXPECT_THAT(targets, HasSubstr("\"lastError\":\"\"")) << targets;

  for (const auto& [unit, device, expected] :
       {std::tuple{1, "drive-a", a}, std::tuple{2, "drive-b", b}}) {
    const std::string promql = "drivegate_device_speed_rpm{device=\"" + std::string(device) + "\"}";
    std::optional<double> seen;
    EXPECT_TRUE(eventually(
        [&, &expected = expected] {
          seen = instant_value(query(promql));
          return seen && *seen == expected;
        },
        5s))
        << device << ": Prometheus has " << (seen ? std::to_string(*seen) : "nothing")
        << ", the PLC read " << expected << "\n"
        << query(promql);
    EXPECT_EQ(plc_speed(unit), expected) << device;  // still turning at that speed
  }
  // One series per device: the labels tell them apart.
  EXPECT_EQ(instant_value(query("count(drivegate_device_speed_rpm)")).value_or(0), 2);
  EXPECT_EQ(instant_value(query("sum(drivegate_device_online)")).value_or(0), 2);

  // Prometheus keeps its connection between scrapes (the case docs/performance.md measures for
  // the Modbus side's p99): the daemon's own HTTP counters, scraped, show requests growing on
  // the connections it had already accepted.
  const auto accepted = instant_value(query("drivegate_http_connections_accepted_total"));
  const auto requests = instant_value(query("drivegate_http_requests_total"));
  ASSERT_TRUE(accepted && requests) << query("{__name__=~\"drivegate_http_.*\"}");
  EXPECT_TRUE(eventually(
      [&] {
        return instant_value(query("drivegate_http_requests_total")).value_or(0) >= *requests + 3;
      },
      10s));
  // At most one new connection over three scrapes or more (a scrape that times out on a loaded
  // machine makes Prometheus reconnect once); a new connection per scrape would be three.
  EXPECT_LE(instant_value(query("drivegate_http_connections_accepted_total")).value_or(1e9),
            *accepted + 1);
  EXPECT_EQ(instant_value(query("drivegate_http_bad_requests_total")), 0);
  EXPECT_EQ(prometheus.stop(), 0) << slurp(dir_ / "prometheus.log");
}

// Every adapter whose scenario registered itself (tests/support/e2e_adapters.h) and whose plugin
// is built, one bus and one drive each, all running, as `drivegate demo` runs them.
class MetricsE2EEveryAdapter : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const auto& a : e2e_adapters()) {
      if (fs::exists(plugin_dir() / ("drivegate-" + a.id + ".so"))) cases_.push_back(a);
    }
    if (cases_.empty()) GTEST_SKIP() << "no adapter built";
    std::string toml = "[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port_) + "\"\n";
    int unit = 1;
    for (const auto& a : cases_) {
      sims_.push_back(std::make_unique<Sim>(a.id, dir_ / a.id, a.sim_args));
      toml += "\n[[bus]]\nname = \"" + a.id + "\"\nport = \"" + (dir_ / a.id).string() + "\"\n" +
              a.bus_extra + "\n[[device]]\nname = \"" + a.id + "-drive\"\nbus = \"" + a.id +
              "\"\nadapter = \"" + a.id + "\"\nunit_id = " + std::to_string(unit++) + "\n" +
              a.device_extra;
    }
    daemon_ =
        std::make_unique<Daemon>(dir_, toml, std::vector<std::string>{}, dir_ / "drivegated.log");
    plc_ = std::make_unique<Plc>(daemon_->port());
    ASSERT_TRUE(plc_->connect());
    for (std::size_t i = 0; i < cases_.size(); ++i) {
      plc_->unit(unit_of(cases_[i].id));
      ASSERT_TRUE(eventually(
          [&] {
            const auto r = plc_->input(reg::status, 1);
            return r.ok() && (r.regs[0] & reg::online) != 0;
          },
          15s))
          << cases_[i].id << " never online:\n"
          << slurp(dir_ / "drivegated.log");
      ASSERT_EQ(
          plc_->write(reg::command, {1 /*run_forward*/, static_cast<std::uint16_t>(cases_[i].rpm)}),
          0)
          << cases_[i].id;
    }
    ASSERT_TRUE(eventually([&] { return http_get(http_port_, "/metrics").status == 200; }, 5s));
  }
  // The unit id of the adapter's drive; 0 if it is not built.
  int unit_of(const std::string& id) const {
    for (std::size_t i = 0; i < cases_.size(); ++i) {
      if (cases_[i].id == id) return static_cast<int>(i) + 1;
    }
    return 0;
  }
  // Whether every adapter of the source tree (a folder with a plugin.cpp) runs here.
  [[nodiscard]] bool every_adapter() const {
    std::size_t tree = 0;
    for (const auto& e : fs::directory_iterator(fs::path(DRIVEGATE_SOURCE_DIR) / "adapters")) {
      tree += fs::exists(e.path() / "plugin.cpp") ? 1 : 0;
    }
    return cases_.size() == tree;
  }

  TempDir dir_;
  int http_port_ = free_port();
  std::vector<E2eAdapter> cases_;
  std::vector<std::unique_ptr<Sim>> sims_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Plc> plc_;
};

TEST_F(MetricsE2EEveryAdapter, PromtoolFindsNothingToLint) {
  const HttpReply r = http_get(http_port_, "/metrics");
  ASSERT_EQ(r.status, 200);
  // Measurements in base units and state sets, from the adapters' own points.
  EXPECT_THAT(r.body, HasSubstr("drivegate_device_point_"));
  EXPECT_THAT(r.body, HasSubstr("drivegate_device_command{"));
  EXPECT_EQ(promtool_complaints(dir_.path(), r.body), "") << "promtool lint complaints";
}

// mdriver-2400's simulated drive reports its IPM temperature (R8, in degC); the PLC reads it over
// Modbus and Prometheus reads the same number from drivegate_device_point_celsius.
TEST_F(MetricsE2EEveryAdapter, PrometheusReadsTheTemperatureTheDriveReports) {
  const int unit = unit_of("mdriver-2400");
  if (unit == 0) GTEST_SKIP() << "mdriver-2400 is not built";
  Sim& sim = *sims_.at(static_cast<std::size_t>(unit - 1));
  EXPECT_THAT(sim.control("temp 57"), HasSubstr("temp=57"));
  constexpr int kIpmTemperature = 36;  // input register (`drivegate regmap`, mdriver-2400 README)
  plc_->unit(unit);
  ASSERT_TRUE(eventually(
      [&] {
        const auto r = plc_->input(kIpmTemperature, 1);
        return r.ok() && r.regs[0] == 57;
      },
      10s))
      << sim.control("state");

  Prometheus prometheus(dir_.path(), http_port_);
  ASSERT_TRUE(prometheus.scraping()) << prometheus.query("up") << "\n"
                                     << slurp(dir_ / "prometheus.log");
  const std::string temperature =
      "drivegate_device_point_celsius{device=\"mdriver-2400-drive\",point=\"ipm_temperature\"}";
  std::optional<double> seen;
  EXPECT_TRUE(eventually(
      [&] {
        seen = prometheus.value(temperature);
        return seen == 57;
      },
      10s))
      << "Prometheus has " << (seen ? std::to_string(*seen) : "nothing") << "\n"
      << prometheus.query(temperature);
  // The command in force, a state set: run_forward's series is 1, stop's 0.
  const std::string command = "drivegate_device_command{device=\"mdriver-2400-drive\",command=";
  EXPECT_EQ(prometheus.value(command + "\"run_forward\"}"), 1);
  EXPECT_EQ(prometheus.value(command + "\"stop\"}"), 0);
  // The runs the PLC wrote, counted by source and result: one to each drive.
  EXPECT_EQ(prometheus.value("sum(drivegate_writes_total{source=\"modbus\",result=\"ok\"})"),
            static_cast<double>(cases_.size()))
      << prometheus.query("drivegate_writes_total");
  // The process metrics of the daemon itself.
  EXPECT_GT(prometheus.value("process_resident_memory_bytes").value_or(0), 0);
  EXPECT_EQ(prometheus.stop(), 0) << slurp(dir_ / "prometheus.log");
}

// Every metric name and label the dashboard's queries use is in what this daemon exports, on a
// drive of every adapter: the names come from the running daemon, not from a list.
TEST_F(MetricsE2EEveryAdapter, TheGrafanaDashboardQueriesOnlyWhatTheDaemonExports) {
  if (!every_adapter()) GTEST_SKIP() << "the dashboard shows every adapter's kinds of points";
  // A Modbus exception (command 9 is none), so that the by-code family has samples and labels.
  plc_->unit(1);
  EXPECT_NE(plc_->write(reg::command, {9}), 0);
  const HttpReply r = http_get(http_port_, "/metrics");
  ASSERT_EQ(r.status, 200);
  std::ofstream(dir_ / "metrics.txt") << r.body;
  const fs::path src = DRIVEGATE_SOURCE_DIR;
  const std::string cmd = kSystemPython + " '" + (src / "tools/check_grafana.py").string() + "' '" +
                          (src / "packaging/grafana/drivegate.json").string() + "' '" +
                          (dir_ / "metrics.txt").string() + "' > '" +
                          (dir_ / "check.out").string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string out = slurp(dir_ / "check.out");
  ASSERT_TRUE(WIFEXITED(status)) << out;
  EXPECT_EQ(WEXITSTATUS(status), 0) << out;
  EXPECT_THAT(out, HasSubstr("metric names: 0 problems")) << out;
}

}  // namespace
}  // namespace drivegate::test::metrics_e2e_test
