// MQTT end-to-end test support: the fixture of the Sparkplug B northbound's end-to-end tests
// (tests/e2e/mqtt_e2e_test.cpp) and of the attacks on it (tests/stress/mqtt_stress_test.cpp): the
// real drivegated on simulated drives of the tests' own (`drivegate sim test-drive` on ptys,
// tests/support/test_adapter), a real mosquitto
// broker on loopback (mosquitto.h) and an independent Sparkplug host, Eclipse Tahu's schema and
// encoder from npm over MQTT.js (sparkplug_peer.h). Nothing here decodes a payload with
// drivegate's own code.
//
// Each test starts its own broker, peer, simulators and daemon. tools/deps.sh installs mosquitto,
// node and the peer's node_modules; without them the tests skip, saying which is missing.
#pragma once

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "e2e.h"
#include "http_get.h"
#include "mosquitto.h"
#include "sparkplug_peer.h"

namespace drivegate::test {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

inline constexpr const char* kGroup = "plant1";
inline constexpr const char* kEdge = "gw01";
inline constexpr std::uint16_t kFailsafeBit = 1 << 5;
inline constexpr int kAccelTime = 16;  // test-drive's holding register accel_time

inline bool executable_in_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  std::string d;
  while (std::getline(dirs, d, ':')) {
    if (!d.empty() && ::access((fs::path(d) / name).c_str(), X_OK) == 0) return true;
  }
  return false;
}

// Why the tests cannot run here, or nullopt.
inline std::optional<std::string> missing_dependency() {
  if (::access(Broker::kMosquitto.c_str(), X_OK) != 0) {
    return Broker::kMosquitto.string() + " is not installed (tools/deps.sh installs mosquitto)";
  }
  if (!executable_in_path("node")) return std::string("node is not installed (tools/deps.sh)");
  for (const char* module : {"sparkplug-payload", "mqtt", "long"}) {
    if (!fs::exists(peer_dir() / "node_modules" / module / "package.json")) {
      return "the Sparkplug peer's node_modules lack '" + std::string(module) + "' in " +
             (peer_dir() / "node_modules").string() + " (tools/deps.sh runs npm ci there)";
    }
  }
  return std::nullopt;
}

inline std::string node_topic(const std::string& type) {
  return std::string("spBv1.0/") + kGroup + "/" + type + "/" + kEdge;
}
inline std::string device_topic(const std::string& type, const std::string& device) {
  return node_topic(type) + "/" + device;
}

inline std::string describe(const Message& m) {
  std::ostringstream s;
  s << m.kind << " " << m.topic;
  if (m.seq) s << " seq=" << *m.seq;
  if (m.kind != "msg") s << " " << m.text;
  for (const auto& x : m.metrics) s << " [" << x.name << ":" << x.type << "=" << x.value << "]";
  return s.str();
}

inline std::string describe(const std::vector<Message>& h) {
  std::string out;
  for (const auto& m : h) out += "  " + describe(m) + "\n";
  return out;
}

inline bool is(const Message& m, std::string_view type, std::string_view device = {}) {
  return m.kind == "msg" && m.message_type() == type && (device.empty() || m.device() == device);
}

// The seq of every message the edge node published (NBIRTH, DBIRTH, NDATA, DDATA, DDEATH), in
// history order: each NBIRTH is 0, each following message the one before + 1 (mod 256). NDEATH
// carries no seq (spec 6.4.x: bdSeq only) and ends nothing: the next session starts at NBIRTH.
inline void expect_seq_consecutive(const std::vector<Message>& history) {
  std::optional<std::uint64_t> last;
  int checked = 0;
  for (const auto& m : history) {
    if (m.kind != "msg") continue;
    const auto t = m.message_type();
    if (t == "NCMD" || t == "DCMD" || t == "NDEATH" || t == "STATE") continue;
    ASSERT_TRUE(m.seq.has_value()) << "no seq in " << describe(m);
    EXPECT_TRUE(m.timestamp.has_value()) << "no timestamp in " << describe(m);
    if (t == "NBIRTH") {
      EXPECT_EQ(*m.seq, 0u) << describe(m);
      last = 0;
      continue;
    }
    if (!last) {
      ADD_FAILURE() << "a message before any NBIRTH: " << describe(m);
      continue;
    }
    EXPECT_EQ(*m.seq, (*last + 1) % 256) << describe(m) << "\nhistory:\n" << describe(history);
    last = *m.seq;
    ++checked;
  }
  EXPECT_GT(checked, 0);
  // And a device's DDATA and DDEATH only while it is born: after its DBIRTH in this session and
  // not after its DDEATH.
  std::map<std::string, bool> born;
  for (const auto& m : history) {
    if (m.kind != "msg") continue;
    const auto t = m.message_type();
    if (t == "NBIRTH" || t == "NDEATH") born.clear();
    if (t == "DBIRTH") born[m.device()] = true;
    if (t == "DDATA" || t == "DDEATH") {
      EXPECT_TRUE(born[m.device()]) << describe(m) << " of a device not born\nhistory:\n"
                                    << describe(history);
    }
    if (t == "DDEATH") born[m.device()] = false;
  }
}

// A ramping drive's speed as a host can put it together from `history` (every DBIRTH and DDATA of
// `device`, of edge node `node` or any when empty, live and historical) by the metrics'
// timestamps, those in [from_ms, to_ms]: how many speeds, the longest gap between two of them,
// how many speeds between the lowest and the highest it never got, and how many it got both live
// and as history (the same time, the same value).
struct RampSeen {
  std::size_t values = 0;
  double worst_gap_ms = 0;
  std::size_t missing = 0;
  std::size_t twice = 0;
};
inline RampSeen ramp_seen(const std::vector<Message>& history, std::string_view node,
                          std::string_view device, std::uint64_t from_ms, std::uint64_t to_ms) {
  std::set<std::pair<std::uint64_t, std::int64_t>> all;
  std::set<std::pair<std::uint64_t, std::int64_t>> live;
  std::set<std::pair<std::uint64_t, std::int64_t>> historical;
  for (const auto& m : history) {
    if (!is(m, "DDATA", device) && !is(m, "DBIRTH", device)) continue;
    if (!node.empty() && m.node() != node) continue;
    const Metric* s = m.metric("speed_rpm");
    if (s == nullptr || !s->timestamp || *s->timestamp < from_ms || *s->timestamp > to_ms) continue;
    const std::pair<std::uint64_t, std::int64_t> v{*s->timestamp, s->as_int()};
    all.insert(v);
    (s->has_flag("historical") ? historical : live).insert(v);
  }
  RampSeen r;
  r.values = all.size();
  std::set<std::int64_t> speeds;
  for (auto it = all.begin(); it != all.end(); ++it) {
    speeds.insert(it->second);
    if (it != all.begin()) {
      r.worst_gap_ms =
          std::max(r.worst_gap_ms, static_cast<double>(it->first - std::prev(it)->first));
    }
  }
  if (!speeds.empty()) {
    r.missing = static_cast<std::size_t>(*speeds.rbegin() - *speeds.begin() + 1) - speeds.size();
  }
  for (const auto& v : historical) r.twice += live.contains(v) ? 1 : 0;
  return r;
}

// The Command/Last Point and Command/Last Result of the next DDATA of `device` carrying them,
// as `peer` sees it.
inline std::optional<std::pair<std::string, std::string>> wait_command_result(
    SparkplugPeer& peer, const std::string& device,
    std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  const auto m = peer.wait_for(
      [&](const Message& x) {
        return is(x, "DDATA", device) && x.metric("Command/Last Result") != nullptr;
      },
      timeout);
  if (!m) return std::nullopt;
  const auto* point = m->metric("Command/Last Point");
  const auto* result = m->metric("Command/Last Result");
  EXPECT_EQ(result->type, "String");
  EXPECT_NE(point, nullptr) << describe(*m);
  return std::pair{point != nullptr ? point->value : "", result->value};
}

// A second broker and a Sparkplug host on it, for the tests of brokers = [...].
struct OtherBroker {
  explicit OtherBroker(const fs::path& peer_log)
      : broker(dir), peer(broker.port(), [&] {
          SparkplugPeer::Options o;
          o.stderr_file = peer_log;
          return o;
        }()) {}
  TempDir dir;
  Broker broker;
  SparkplugPeer peer;
};

struct Drive {
  std::string name;
  int unit;
  fs::path link;
  std::string device_extra;  // more keys of its [[device]] table
  std::unique_ptr<Sim> sim;
};

class MqttE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto why = missing_dependency()) GTEST_SKIP() << *why;
    started_ = std::chrono::steady_clock::now();
    broker_ = std::make_unique<Broker>(dir_);
    SparkplugPeer::Options o;
    o.stderr_file = dir_ / "peer.log";
    peer_ = std::make_unique<SparkplugPeer>(broker_->port(), o);
    add_drive("drive-a");
    add_drive("drive-b");
  }
  void TearDown() override {
    if (HasFailure()) {
      std::cerr << "--- drivegated.log:\n"
                << daemon_log() << "--- peer history:\n"
                << (peer_ ? describe(peer_->history()) : "") << "--- peer.log:\n"
                << slurp(dir_ / "peer.log") << "--- mosquitto.log:\n"
                << broker_log() << "\n";
    }
    if (started_) {
      const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                          std::chrono::steady_clock::now() - *started_)
                          .count();
      RecordProperty("took_ms", static_cast<int>(ms));
    }
  }

  Drive& add_drive(const std::string& name, const std::string& device_extra = "") {
    Drive d{name, static_cast<int>(drives_.size()) + 1, dir_ / name, device_extra, nullptr};
    d.sim = std::make_unique<Sim>("test-drive", d.link);
    drives_.push_back(std::move(d));
    return drives_.back();
  }
  Drive& drive(const std::string& name) {
    for (auto& d : drives_) {
      if (d.name == name) return d;
    }
    throw std::runtime_error("no drive " + name);
  }

  std::string config(const std::string& mqtt_extra) const {
    std::string toml;
    for (const auto& d : drives_) {
      toml += "[[bus]]\nname = \"line-" + d.name + "\"\nport = \"" + d.link.string() +
              "\"\n\n[[device]]\nname = \"" + d.name + "\"\nbus = \"line-" + d.name +
              "\"\nadapter = \"test-drive\"\nunit_id = " + std::to_string(d.unit) +
              "\npoll_ms = " + std::to_string(poll_ms_) + "\n" + d.device_extra + "\n";
    }
    std::string broker = "broker = \"" + broker_->url() + "\"";
    if (!brokers_.empty()) {
      broker = "brokers = [";
      for (std::size_t i = 0; i < brokers_.size(); ++i) {
        broker += (i == 0 ? "\"" : ", \"") + brokers_[i] + "\"";
      }
      broker += "]";
    }
    return toml + "[mqtt]\n" + broker + "\ngroup_id = \"" + kGroup + "\"\nedge_node_id = \"" +
           kEdge + "\"\n" + mqtt_extra;
  }

  void start_daemon(const std::string& mqtt_extra = "") {
    daemon_ =
        std::make_unique<Daemon>(dir_, config(mqtt_extra), daemon_args_, dir_ / "drivegated.log");
    plc_ = std::make_unique<Plc>(daemon_->port());
    ASSERT_TRUE(plc_->connect());
    for (const auto& d : drives_) wait_online(d.unit);
  }
  void wait_online(int unit) {
    plc_->unit(unit);
    ASSERT_TRUE(eventually(
        [&] {
          const auto r = plc_->input(reg::status, 1);
          return r.ok() && (r.regs[0] & reg::online) != 0;
        },
        10s))
        << "unit " << unit << " never online";
  }
  std::string daemon_log() const { return slurp(dir_ / "drivegated.log"); }
  // The broker's log so far, its current run included.
  std::string broker_log() const {
    return broker_ ? broker_->log() + slurp(dir_ / "mosquitto.log.part") : "";
  }
  // How many times the daemon connected to the broker, from the broker's log.
  int sessions() const {
    const std::string log = broker_log();
    int n = 0;
    for (auto at = log.find(" as drivegate-gw01 "); at != std::string::npos;
         at = log.find(" as drivegate-gw01 ", at + 1)) {
      ++n;
    }
    return n;
  }

  std::uint16_t input(int unit, int address) {
    plc_->unit(unit);
    const auto r = plc_->input(address, 1);
    return r.ok() ? r.regs.at(0) : 0xDEAD;
  }
  std::uint16_t holding(int unit, int address) {
    plc_->unit(unit);
    const auto r = plc_->holding(address, 1);
    return r.ok() ? r.regs.at(0) : 0xDEAD;
  }
  int speed(int unit) { return static_cast<std::int16_t>(input(unit, reg::speed)); }

  // Reads everything the peer prints for `d` (into history()).
  void pump(std::chrono::milliseconds d) {
    peer_->wait_for([](const Message&) { return false; }, d);
  }
  std::optional<Message> wait(std::string_view type, std::string_view device = {},
                              std::chrono::milliseconds timeout = 10s) {
    return peer_->wait_for([&](const Message& m) { return is(m, type, device); }, timeout);
  }
  std::size_t count(std::string_view type, std::string_view device = {}) const {
    std::size_t n = 0;
    for (const auto& m : peer_->history()) n += is(m, type, device) ? 1 : 0;
    return n;
  }
  // The next NBIRTH and then a DBIRTH for each drive (of drives_).
  struct Births {
    Message node;
    std::map<std::string, Message> devices;
  };
  Births wait_births(std::chrono::milliseconds timeout = 10s) {
    Births b;
    auto nb = wait("NBIRTH", {}, timeout);
    EXPECT_TRUE(nb.has_value()) << "no NBIRTH";
    if (!nb) return b;
    b.node = *nb;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (b.devices.size() < drives_.size() && std::chrono::steady_clock::now() < deadline) {
      const auto m = peer_->wait_for([](const Message& x) { return is(x, "DBIRTH"); },
                                     std::chrono::duration_cast<std::chrono::milliseconds>(
                                         deadline - std::chrono::steady_clock::now()));
      if (!m) break;
      EXPECT_FALSE(b.devices.contains(m->device())) << "two DBIRTHs: " << describe(*m);
      b.devices[m->device()] = *m;
    }
    EXPECT_EQ(b.devices.size(), drives_.size()) << "DBIRTHs missing";
    return b;
  }

  void dcmd(const std::string& device, const std::string& metrics_json) {
    peer_->publish(device_topic("DCMD", device), R"({"metrics":[)" + metrics_json + "]}");
  }
  // The same on this test's broker.
  std::optional<std::pair<std::string, std::string>> wait_command_result(
      const std::string& device, std::chrono::milliseconds timeout = 10s) {
    return test::wait_command_result(*peer_, device, timeout);
  }

  TempDir dir_;
  int poll_ms_ = 100;
  std::vector<std::string> daemon_args_;  // drivegated's, after --config, --listen, --plugin-dir
  std::vector<std::string> brokers_;      // [mqtt] brokers = [...]; empty: broker = broker_'s URL
  std::optional<std::chrono::steady_clock::time_point> started_;
  std::unique_ptr<Broker> broker_;
  std::unique_ptr<SparkplugPeer> peer_;
  std::vector<Drive> drives_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Plc> plc_;
};

}  // namespace drivegate::test
