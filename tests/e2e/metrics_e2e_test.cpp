// /metrics end to end: drivegated with [http] on two simulated nidec-washer drives, its Prometheus
// text checked by Debian's promtool (tools/deps.sh installs `prometheus`) and scraped by a real
// Prometheus server on loopback, whose query API must agree with what a PLC reads over Modbus.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <tuple>

#include "e2e.h"
#include "http_get.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

std::string slurp(const fs::path& file) {
  std::ostringstream text;
  text << std::ifstream(file).rdbuf();
  return text.str();
}

// Two drives, each on its own simulated line: "washer-a" (unit 1) and "washer-b" (unit 2).
std::string config(const fs::path& a, const fs::path& b, int http_port) {
  std::string toml;
  int unit = 1;
  for (const auto& [name, port] : {std::pair{"washer-a", a}, std::pair{"washer-b", b}}) {
    toml += "[[bus]]\nname = \"line-" + std::string(name) + "\"\nport = \"" + port.string() +
            "\"\n\n[[device]]\nname = \"" + name + "\"\nbus = \"line-" + name +
            "\"\nadapter = \"nidec-washer\"\nunit_id = " + std::to_string(unit++) +
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

class MetricsE2E : public ::testing::Test {
 protected:
  MetricsE2E()
      : http_port_(free_port()),
        sim_a_("nidec-washer", dir_ / "washer-a"),
        sim_b_("nidec-washer", dir_ / "washer-b"),
        daemon_(dir_, config(dir_ / "washer-a", dir_ / "washer-b", http_port_), {},
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
  EXPECT_THAT(r.body, HasSubstr("drivegate_device_speed_rpm{device=\"washer-a\""));
  EXPECT_THAT(r.body, HasSubstr("drivegate_device_speed_rpm{device=\"washer-b\""));
  std::ofstream(dir_ / "metrics.txt") << r.body;

  const std::string cmd = "promtool check metrics < '" + (dir_ / "metrics.txt").string() + "' > '" +
                          (dir_ / "promtool.out").string() + "' 2>&1";
  const int status = std::system(cmd.c_str());
  const std::string out = slurp(dir_ / "promtool.out");
  ASSERT_TRUE(WIFEXITED(status)) << out;
  ASSERT_NE(WEXITSTATUS(status), 127) << "promtool not found: tools/deps.sh installs prometheus";
  EXPECT_EQ(WEXITSTATUS(status), 0) << out << "\n--- /metrics:\n" << r.body;
  EXPECT_EQ(out, "") << "promtool lint complaints:\n" << out;
}

TEST_F(MetricsE2E, PrometheusScrapesWhatThePlcReads) {
  const int a = run(1, 1 /*run_forward*/, 800);
  const int b = run(2, 2 /*run_reverse*/, 600);
  EXPECT_EQ(a, 800);

  const int prom_port = free_port();
  std::ofstream(dir_ / "prometheus.yml")
      << "global:\n  scrape_interval: 1s\n  scrape_timeout: 1s\n  evaluation_interval: 1s\n"
         "scrape_configs:\n  - job_name: drivegate\n    static_configs:\n"
         "      - targets: ['127.0.0.1:"
      << http_port_ << "']\n";
  fs::create_directories(dir_ / "tsdb");
  Child prometheus({"/usr/bin/prometheus", "--config.file=" + (dir_ / "prometheus.yml").string(),
                    "--storage.tsdb.path=" + (dir_ / "tsdb").string(),
                    "--web.listen-address=127.0.0.1:" + std::to_string(prom_port)},
                   dir_ / "prometheus.log");
  const auto query = [&](const std::string& promql) {
    return http_get(prom_port, "/api/v1/query?query=" + url_encode(promql)).body;
  };
  ASSERT_TRUE(eventually(
      [&] { return instant_value(query("up{job=\"drivegate\"}")).value_or(0) == 1; }, 10s))
      << query("up") << "\n"
      << slurp(dir_ / "prometheus.log");

  // The scrape went through the whole exposition without an error.
  const std::string targets = http_get(prom_port, "/api/v1/targets").body;
  EXPECT_THAT(targets, HasSubstr("\"health\":\"up\"")) << targets;
  EXPECT_THAT(targets, HasSubstr("\"lastError\":\"\"")) << targets;

  for (const auto& [unit, device, expected] :
       {std::tuple{1, "washer-a", a}, std::tuple{2, "washer-b", b}}) {
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
  EXPECT_EQ(prometheus.stop(SIGTERM, 10s), 0) << slurp(dir_ / "prometheus.log");
}

}  // namespace
}  // namespace drivegate::test
