// A fleet on one broker: N real drivegated processes (20 unless
// DRIVEGATE_FLEET_GATEWAYS says otherwise), each with its own simulated drive of the tests' own
// (test-drive) on a pty, its
// own edge node id and its own state directory, one mosquitto, and one Sparkplug host: Eclipse
// Tahu's codec over MQTT.js (tests/mqtt/peer/sparkplug_peer.js), whose checks are this file's,
// written from the specification, not from daemon/mqtt.
//
// What a SCADA host must see of the whole fleet, and is asserted here:
//   - every node's NBIRTH and its drive's DBIRTH, with the metrics a faceplate binds to;
//   - every change, once and in order: per node, seq consecutive in each session, each store's
//     count at the host, and the speed ramp's timestamps without a lost stretch (a hole of a
//     second), across live data, a broker outage and the replay;
//   - a broker outage (DRIVEGATE_FLEET_OUTAGE_S, 30 s) during which every drive's speed climbs:
//     afterwards the births first, then every kept change as historical DDATA in order, each
//     node's count what its store kept, nothing dropped, nothing twice;
//   - a gateway killed with -9: its will NDEATH carries the bdSeq of its last NBIRTH, and its
//     restart is born with the next.
// The same run measures what bench/fleet.sh reports (docs/performance.md): births per second at
// start-up, frame-to-host latency (the metric timestamp is when the drive's reply frame arrived,
// daemon/mqtt/northbound.cpp; the host stamps its receipt on the same clock), the replay rate and
// the live latency meanwhile, CPU and memory of the broker, the host and each gateway. The
// figures go to stderr, and as `key value` lines to DRIVEGATE_FLEET_REPORT when it is set.
// DRIVEGATE_FLEET_LIVE_S (10) is how long the live figures are taken over, and
// DRIVEGATE_FLEET_REPLAY_PER_S, when set, every gateway's [mqtt] replay_per_s.
// DRIVEGATE_FLEET_HALF_OPEN_S, when set, adds a half-open outage after the broker outage: the
// gateways reach the broker through a proxy (tests/support/fault_proxy.h) that stops forwarding
// every connection, new ones included, without closing any, for that long; asserted the same way
// (no change lost), with the time each gateway took to notice and the changes the host then got
// twice (live and as history) as figures. The ramp is then twice as long (0 to 2400 rpm in 240 s,
// the same 1 rpm a poll), for the test outlasts 120 s.
//
// The fixture is MqttE2EFleet: .ci/run's sanitizer passes leave it out with the other MqttE2E
// tests, as a timing run on a real broker.
#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <future>
#include <map>
#include <mutex>
#include <numeric>
#include <set>

#include "fault_proxy.h"
#include "mqtt_e2e.h"
#include "status/process_metrics.h"

namespace drivegate::test {
namespace {

constexpr const char* kFleetGroup = "fleet";
constexpr const char* kHost = "fleet-host";
constexpr const char* kDrive = "drive";
// The ramp every drive runs: 0 to kTarget rpm at one rpm per 100 ms poll (test-drive's accel
// time, kAccelMs, is its time from 0 to 3000 rpm), so every poll reads a new speed and every
// change is a DDATA (min_interval_ms = 0) for as long as the test runs.
constexpr int kTarget = 1200;
constexpr int kAccelMs = 300'000;
constexpr int kPollMs = 100;

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v != nullptr && *v != '\0' ? std::atoi(v) : fallback;
}

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// CPU seconds (user + system) a process has used, read as the daemon's own /metrics reads it.
double cpu_seconds(pid_t pid) {
  const auto stat = parse_proc_stat(slurp("/proc/" + std::to_string(pid) + "/stat"));
  if (!stat) return 0;
  return static_cast<double>(stat->utime_ticks + stat->stime_ticks) /
         static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// A /proc/<pid>/status field in kB (VmRSS, VmHWM), 0 when absent.
long status_kb(pid_t pid, const std::string& key) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ":", 0) == 0) return std::atol(line.c_str() + key.size() + 1);
  }
  return 0;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return -1;
  std::sort(v.begin(), v.end());
  const auto at = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, at == 0 ? 0 : at - 1)];
}

std::string bd_seq(const Message& m) {
  return m.metric("bdSeq") != nullptr ? m.metric("bdSeq")->value : "none";
}

struct Gateway {
  std::string id;  // the edge node id
  std::unique_ptr<TempDir> dir;
  std::unique_ptr<Sim> sim;
  int modbus_port = 0;
  int http_port = 0;
  std::unique_ptr<Daemon> daemon;
  std::string mqtt_extra;  // more [mqtt] keys

  [[nodiscard]] std::string toml(const std::string& broker_url) const {
    return "[[bus]]\nname = \"line\"\nport = \"" + (*dir / "drive").string() +
           "\"\n\n[[device]]\nname = \"" + kDrive +
           "\"\nbus = \"line\"\nadapter = \"test-drive\"\nunit_id = 1\npoll_ms = " +
           std::to_string(kPollMs) +
           "\n[device.options]\naccel_time_ms = " + std::to_string(kAccelMs) +
           "\n\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) +
           "\"\n\n[mqtt]\nbroker = \"" + broker_url + "\"\ngroup_id = \"" + kFleetGroup +
           "\"\nedge_node_id = \"" + id + "\"\nprimary_host_id = \"" + kHost +
           "\"\nmin_interval_ms = 0\n" + mqtt_extra;
  }
  // The ports are handed out by the fixture (Fleet::port), never twice. Another process's
  // outgoing connection can still take one before this daemon binds it: the daemon then exits
  // saying so, and is started again on new ones; any other start-up failure is the test's.
  void start(const std::string& broker_url, const std::function<int()>& new_port) {
    for (int attempt = 1;; ++attempt) {
      try {
        daemon = std::make_unique<Daemon>(
            *dir, toml(broker_url),
            std::vector<std::string>{"--state-dir", (*dir / "state").string()},
            *dir / "drivegated.log", modbus_port);
        return;
      } catch (const std::runtime_error&) {
        if (attempt == 3 ||
            slurp(*dir / "drivegated.log").find("Address already in use") == std::string::npos) {
          throw;
        }
        modbus_port = new_port();
        http_port = new_port();
      }
    }
  }
  [[nodiscard]] double metric(const std::string& name) const {
    return test::metric(http_port, name);
  }
};

class MqttE2EFleet : public ::testing::Test {
 protected:
  void SetUp() override {
    if (const auto why = missing_dependency()) GTEST_SKIP() << *why;
    size_ = env_int("DRIVEGATE_FLEET_GATEWAYS", 20);
    outage_ = std::chrono::seconds(env_int("DRIVEGATE_FLEET_OUTAGE_S", 30));
    live_ = std::chrono::seconds(env_int("DRIVEGATE_FLEET_LIVE_S", 10));
    const int replay_per_s = env_int("DRIVEGATE_FLEET_REPLAY_PER_S", 0);
    half_open_ = std::chrono::seconds(env_int("DRIVEGATE_FLEET_HALF_OPEN_S", 0));
    if (half_open_.count() > 0) {
      target_ = 2 * kTarget;  // at the same rate: twice as long
    }
    broker_ = std::make_unique<Broker>(dir_);
    if (half_open_.count() > 0) proxy_ = std::make_unique<FaultProxy>(broker_->port());
    SparkplugPeer::Options o;
    o.stderr_file = dir_ / "host.log";
    o.client_id = kHost;
    o.subscriptions = {std::string("spBv1.0/") + kFleetGroup + "/#"};
    host_ = std::make_unique<SparkplugPeer>(broker_->port(), o);
    announce_host();
    for (int i = 1; i <= size_; ++i) {
      Gateway g;
      g.id = (i < 10 ? "gw0" : "gw") + std::to_string(i);
      g.dir = std::make_unique<TempDir>();
      fs::create_directories(*g.dir / "state");
      g.sim = std::make_unique<Sim>("test-drive", *g.dir / "drive");
      g.modbus_port = port();
      g.http_port = port();
      if (replay_per_s > 0) g.mqtt_extra = "replay_per_s = " + std::to_string(replay_per_s) + "\n";
      fleet_.push_back(std::move(g));
    }
    if (const char* path = std::getenv("DRIVEGATE_FLEET_REPORT")) report_.open(path);
  }
  void TearDown() override {
    if (!HasFailure()) return;
    for (const auto& g : fleet_) {
      std::cerr << "--- " << g.id << " drivegated.log (tail):\n"
                << tail(slurp(*g.dir / "drivegated.log"));
    }
    std::cerr << "--- host.log:\n"
              << slurp(dir_ / "host.log") << "--- mosquitto.log (tail):\n"
              << tail(broker_->log() + slurp(dir_ / "mosquitto.log.part")) << "\n";
  }
  static std::string tail(const std::string& s) {
    return s.size() > 3000 ? "..." + s.substr(s.size() - 3000) : s;
  }

  // Sparkplug 3.0 primary host STATE (spec 7.x): retained, QoS 1, as a host publishes it on every
  // connect. The nodes wait for it before their births.
  void announce_host() {
    const auto ms = static_cast<std::uint64_t>(unix_now() * 1000);
    host_->publish_text(std::string("spBv1.0/STATE/") + kHost, host_state(true, ms), true, 1);
  }
  // Reads what the host prints for `d` (into history()); says the host is online again when its
  // broker comes back.
  void pump(std::chrono::milliseconds d) {
    const auto deadline = std::chrono::steady_clock::now() + d;
    while (true) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return;
      const auto m = host_->next(left);
      if (m && m->kind == "reconnected") announce_host();
    }
  }
  bool pump_until(const std::function<bool()>& done, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!done()) {
      if (std::chrono::steady_clock::now() >= deadline) return false;
      pump(100ms);
    }
    return true;
  }
  std::vector<Message> node_history(const std::string& id) const {
    std::vector<Message> out;
    for (const auto& m : host_->history()) {
      if (m.kind == "msg" && m.node() == id) out.push_back(m);
    }
    return out;
  }
  // How many `type` messages of node `id` the host received since `since` (unix s).
  std::size_t count(const std::string& id, std::string_view type, double since) const {
    std::size_t n = 0;
    for (const auto& m : host_->history()) {
      n += m.node() == id && is(m, type) && m.received_unix >= since;
    }
    return n;
  }
  bool every_node_has(std::string_view type, std::size_t n) const {
    std::map<std::string, std::size_t> seen;
    for (const auto& m : host_->history()) {
      if (is(m, type)) ++seen[m.node()];
    }
    return std::all_of(fleet_.begin(), fleet_.end(),
                       [&](const Gateway& g) { return seen[g.id] >= n; });
  }

  // A free port no gateway of this fleet has been given (gateways start on several threads).
  int port() {
    const std::lock_guard lock(ports_mutex_);
    int p = free_port();
    while (!ports_.insert(p).second) p = free_port();
    return p;
  }

  void figure(const std::string& key, double value) {
    std::cerr << "fleet: " << key << " " << value << "\n";
    if (report_) report_ << key << " " << value << "\n";
  }
  // CPU seconds of every process of the fleet, by role.
  struct Cpu {
    std::vector<double> gateways;
    double broker = 0;
    double host = 0;
  };
  Cpu cpu() {
    Cpu c;
    for (const auto& g : fleet_) c.gateways.push_back(cpu_seconds(g.daemon->process().pid()));
    c.broker = cpu_seconds(broker_->pid());
    c.host = cpu_seconds(host_->process().pid());
    return c;
  }
  void cpu_figures(const std::string& phase, const Cpu& a, const Cpu& b, double seconds) {
    std::vector<double> share;
    for (std::size_t i = 0; i < a.gateways.size(); ++i) {
      share.push_back((b.gateways[i] - a.gateways[i]) / seconds);
    }
    figure(phase + "_gateway_cpu_mean",
           std::accumulate(share.begin(), share.end(), 0.0) / static_cast<double>(share.size()));
    figure(phase + "_gateway_cpu_max", *std::max_element(share.begin(), share.end()));
    figure(phase + "_broker_cpu", (b.broker - a.broker) / seconds);
    figure(phase + "_host_cpu", (b.host - a.host) / seconds);
  }
  // Frame-to-host latency of the live speed DDATA the host received in [from, to) (unix s), ms.
  std::vector<double> live_latencies(double from, double to) const {
    std::vector<double> out;
    for (const auto& m : host_->history()) {
      if (!is(m, "DDATA") || m.received_unix < from || m.received_unix >= to) continue;
      const Metric* s = m.metric("speed_rpm");
      if (s == nullptr || s->has_flag("historical") || !s->timestamp) continue;
      out.push_back(m.received_unix * 1000.0 - static_cast<double>(*s->timestamp));
    }
    return out;
  }
  void latency_figures(const std::string& phase, const std::vector<double>& ms) {
    figure(phase + "_latency_samples", static_cast<double>(ms.size()));
    figure(phase + "_latency_p50_ms", percentile(ms, 50));
    figure(phase + "_latency_p99_ms", percentile(ms, 99));
    figure(phase + "_latency_max_ms", percentile(ms, 100));
  }

  // Where the gateways connect: the broker, or the proxy before it.
  [[nodiscard]] std::string broker_url() const { return proxy_ ? proxy_->url() : broker_->url(); }
  TempDir dir_;
  int size_ = 20;
  std::chrono::seconds outage_{30};
  std::chrono::seconds live_{10};
  std::chrono::seconds half_open_{0};
  int target_ = kTarget;
  std::unique_ptr<Broker> broker_;
  std::unique_ptr<FaultProxy> proxy_;  // with a half-open outage
  std::unique_ptr<SparkplugPeer> host_;
  std::vector<Gateway> fleet_;
  std::ofstream report_;
  std::mutex ports_mutex_;
  std::set<int> ports_;  // handed out to the gateways
};

TEST_F(MqttE2EFleet, EveryChangeOfEveryGatewayReachesTheHostThroughAnOutageAndAKill) {
  figure("gateways", size_);
  // --- Start-up: every gateway at once; every node and drive born.
  const double t_start = unix_now();
  {
    std::vector<std::future<void>> starting;
    for (auto& g : fleet_) {
      starting.push_back(std::async(std::launch::async,
                                    [&] { g.start(broker_url(), [this] { return port(); }); }));
    }
    for (auto& f : starting) f.get();  // rethrows a gateway that did not start
  }
  ASSERT_TRUE(pump_until([&] { return every_node_has("DBIRTH", 1); }, 60s))
      << "not every gateway was born";
  double last_birth = 0;
  for (const auto& g : fleet_) {
    SCOPED_TRACE(g.id);
    const auto h = node_history(g.id);
    const auto nb =
        std::find_if(h.begin(), h.end(), [](const Message& m) { return is(m, "NBIRTH"); });
    const auto db =
        std::find_if(h.begin(), h.end(), [](const Message& m) { return is(m, "DBIRTH"); });
    ASSERT_TRUE(nb != h.end() && db != h.end());
    EXPECT_EQ(bd_seq(*nb), "0") << "a fresh state directory";
    EXPECT_NE(nb->metric("Node Control/Rebirth"), nullptr);
    EXPECT_EQ(db->device(), kDrive);
    for (const char* name : {"speed_rpm", "status", "fault_code", "setpoint_rpm", "command",
                             "status_online", "status_running"}) {
      EXPECT_NE(db->metric(name), nullptr) << name << " missing: " << describe(*db);
    }
    if (db->metric("status_online") != nullptr) {
      EXPECT_EQ(db->metric("status_online")->value, "true");
    }
    last_birth = std::max(last_birth, db->received_unix);
  }
  ASSERT_FALSE(HasFailure());
  figure("startup_all_births_s", last_birth - t_start);
  figure("startup_births_per_s", 2.0 * size_ / (last_birth - t_start));

  // --- Live: every drive ramps up; the host sees each new speed.
  for (auto& g : fleet_) {
    Plc plc(g.daemon->port());
    ASSERT_TRUE(plc.connect()) << g.id;
    ASSERT_EQ(plc.write(reg::command, {1 /*run_forward*/, static_cast<std::uint16_t>(target_)}), 0)
        << g.id;
  }
  pump(2s);  // the ramps under way
  const double live_from = unix_now();
  Cpu cpu_a = cpu();
  pump(live_);
  const double live_to = unix_now();
  Cpu cpu_b = cpu();
  const auto live_ms = live_latencies(live_from, live_to);
  latency_figures("live", live_ms);
  // Wide margins: a property (nothing queues up), not a figure; the figures are bench/fleet.sh's.
  EXPECT_LT(percentile(live_ms, 99), 1000) << "live data late";
  cpu_figures("live", cpu_a, cpu_b, live_to - live_from);
  figure("live_ddata_per_s",
         static_cast<double>(std::count_if(host_->history().begin(), host_->history().end(),
                                           [&](const Message& m) {
                                             return is(m, "DDATA") &&
                                                    m.received_unix >= live_from &&
                                                    m.received_unix < live_to;
                                           })) /
             (live_to - live_from));

  // --- The broker goes away for the outage; the ramps go on and every gateway keeps them.
  ASSERT_EQ(broker_->stop(), 0);
  const double outage_from = unix_now();
  pump(outage_);
  double store_bytes = 0;
  for (const auto& g : fleet_) {
    EXPECT_EQ(g.metric("drivegate_mqtt_connected"), 0) << g.id;
    EXPECT_GE(g.metric("drivegate_mqtt_store_records"), static_cast<double>(outage_.count()) * 5.0)
        << g.id << ": the ramp was not kept";
    store_bytes = std::max(store_bytes, g.metric("drivegate_mqtt_store_bytes"));
  }
  figure("outage_store_bytes_max", store_bytes);
  broker_->start();
  const double outage_to = unix_now();
  figure("outage_s", outage_to - outage_from);
  cpu_a = cpu();
  // Every node reborn, and every store replayed to the end.
  ASSERT_TRUE(pump_until(
      [&] {
        return every_node_has("NBIRTH", 2) &&
               std::all_of(fleet_.begin(), fleet_.end(), [](const Gateway& g) {
                 return g.metric("drivegate_mqtt_store_records") == 0;
               });
      },
      90s))
      << "not every gateway came back and replayed what it kept";
  pump(1s);
  cpu_b = cpu();
  const double replay_done = unix_now();

  double first_historical = 0;
  double last_historical = 0;
  double last_reconnect = 0;
  std::size_t historical_total = 0;
  std::size_t replayed_after_outage = 0;
  std::vector<double> replay_rates;  // records per second, per gateway
  std::size_t kept_and_in_a_birth = 0;
  std::size_t live_and_kept_total = 0;
  double worst_hole_ms = 0;
  for (const auto& g : fleet_) {
    SCOPED_TRACE(g.id);
    const auto h = node_history(g.id);
    expect_seq_consecutive(h);
    // What was kept comes after the births of the session it is sent in (expect_seq_consecutive:
    // no DDATA of a device not born), in order, each once. Kept are the outage's changes and the
    // few from the start, before the host's STATE let the first births go.
    std::vector<std::pair<std::uint64_t, std::int64_t>> ramp;  // (metric timestamp, speed)
    std::vector<std::int64_t> historical;
    std::set<std::pair<std::uint64_t, std::int64_t>> sent_live;  // (metric timestamp, speed)
    std::set<std::pair<std::uint64_t, std::int64_t>> born_as;
    std::vector<std::string> bd_seqs;
    std::size_t live_and_kept = 0;
    double replay_from = 0;
    double replay_to = 0;
    std::size_t replayed = 0;
    for (const auto& m : h) {
      if (is(m, "NBIRTH")) {
        bd_seqs.push_back(bd_seq(m));
        if (bd_seqs.size() == 2) last_reconnect = std::max(last_reconnect, m.received_unix);
      }
      if (!is(m, "DDATA") && !is(m, "DBIRTH")) continue;
      const Metric* s = m.metric("speed_rpm");
      if (s == nullptr || !s->timestamp) continue;
      ramp.emplace_back(*s->timestamp, s->as_int());
      const std::pair<std::uint64_t, std::int64_t> change{*s->timestamp, s->as_int()};
      if (!s->has_flag("historical")) {
        (is(m, "DBIRTH") ? born_as : sent_live).insert(change);
        continue;
      }
      // Kept, and also sent live: twice, when the broker had it and had not confirmed it yet as
      // the link went (docs/mqtt.md, "Nothing leaves before the broker has it"): counted, and
      // bounded below. Kept while the births waited, and in the birth after it: a state the
      // host may see twice (the birth is no change), counted.
      if (sent_live.contains(change)) ++live_and_kept;
      if (born_as.contains(change)) ++kept_and_in_a_birth;
      historical.push_back(s->as_int());
      if (m.received_unix < outage_to) continue;
      replay_from = replayed == 0 ? m.received_unix : replay_from;
      replay_to = m.received_unix;
      ++replayed;
    }
    if (replayed > 0) {
      first_historical =
          first_historical == 0 ? replay_from : std::min(first_historical, replay_from);
      last_historical = std::max(last_historical, replay_to);
      replayed_after_outage += replayed;
      // Batches go every 100 ms (StoreForward::kReplayPeriod): the last one's period counts.
      replay_rates.push_back(static_cast<double>(replayed) / (replay_to - replay_from + 0.1));
    }
    // The last quarter second or so of live data before the broker went: 10 changes a second.
    EXPECT_LE(live_and_kept, 10u) << "more changes received twice than the unconfirmed ones";
    live_and_kept_total += live_and_kept;
    // A new session, a new bdSeq (one per connection attempt, failed ones too: docs/mqtt.md).
    ASSERT_EQ(bd_seqs.size(), 2u);
    EXPECT_NE(bd_seqs[0], bd_seqs[1]);
    EXPECT_GE(historical.size(), static_cast<std::size_t>(outage_.count() * 5));
    EXPECT_TRUE(std::is_sorted(historical.begin(), historical.end())) << "out of order";
    EXPECT_EQ(std::set<std::int64_t>(historical.begin(), historical.end()).size(),
              historical.size())
        << "a change sent twice";
    // Each node sent what its store kept, and the host got every one of them.
    const double kept = g.metric("drivegate_mqtt_store_kept_total");
    EXPECT_EQ(g.metric("drivegate_mqtt_store_replayed_total"), kept);
    EXPECT_EQ(g.metric("drivegate_mqtt_store_dropped_total"), 0);
    std::size_t historical_ddata = 0;
    for (const auto& m : h) {
      historical_ddata +=
          is(m, "DDATA") && !m.metrics.empty() && m.metrics.front().has_flag("historical");
    }
    EXPECT_EQ(static_cast<double>(historical_ddata), kept) << "kept, but not at the host";
    historical_total += historical_ddata;
    // No hole in the ramp as the host can put it together by the metrics' timestamps: live, then
    // kept, then live again. A poll is every 100 ms; a lost change leaves a hole of 200 ms or
    // more, a lost stretch of the outage seconds.
    std::sort(ramp.begin(), ramp.end());
    ramp.erase(std::unique(ramp.begin(), ramp.end()), ramp.end());
    double hole = 0;
    for (std::size_t i = 1; i < ramp.size(); ++i) {
      if (ramp[i - 1].second >= target_) break;
      EXPECT_GE(ramp[i].second, ramp[i - 1].second) << "the speed went back at " << ramp[i].first;
      hole = std::max(hole, static_cast<double>(ramp[i].first - ramp[i - 1].first));
    }
    EXPECT_LT(hole, 1000) << "changes missing";
    worst_hole_ms = std::max(worst_hole_ms, hole);
  }
  figure("ramp_worst_hole_ms", worst_hole_ms);
  figure("kept_and_in_a_birth", static_cast<double>(kept_and_in_a_birth));
  figure("kept_and_sent_live", static_cast<double>(live_and_kept_total));
  figure("reconnect_last_s", last_reconnect - outage_to);
  figure("kept_records", static_cast<double>(historical_total));
  figure("replayed_after_outage", static_cast<double>(replayed_after_outage));
  ASSERT_EQ(replay_rates.size(), fleet_.size()) << "a gateway replayed nothing";
  figure("replay_fleet_span_s", last_historical - first_historical);
  // The most historical DDATA the host got in one second, from the whole fleet.
  std::map<long, double> per_second;
  for (const auto& m : host_->history()) {
    if (is(m, "DDATA") && m.received_unix >= outage_to && !m.metrics.empty() &&
        m.metrics.front().has_flag("historical")) {
      ++per_second[static_cast<long>(m.received_unix)];
    }
  }
  double peak = 0;
  for (const auto& [second, n] : per_second) peak = std::max(peak, n);
  figure("replay_fleet_peak_records_per_s", peak);
  figure("replay_gateway_records_per_s_min",
         *std::min_element(replay_rates.begin(), replay_rates.end()));
  figure("replay_gateway_records_per_s_median", percentile(replay_rates, 50));
  // Live data while the stores replay: paced replay batches do not hold it back.
  const auto during_replay_ms = live_latencies(first_historical, last_historical + 0.001);
  latency_figures("replay", during_replay_ms);
  EXPECT_FALSE(during_replay_ms.empty()) << "no live data while the stores replayed";
  EXPECT_LT(percentile(during_replay_ms, 99), 1000) << "live data held back by the replay";
  cpu_figures("reconnect_replay", cpu_a, cpu_b, replay_done - outage_to);
  ASSERT_FALSE(HasFailure());

  if (half_open_.count() > 0) {
    // --- A half-open outage: every connection stops forwarding without being closed, new ones
    // too; the gateways go on publishing into their links until they find them dead.
    std::size_t births_before = 0;
    for (const auto& m : host_->history()) births_before += is(m, "NBIRTH");
    const double from = unix_now();
    proxy_->hold_new(true);
    proxy_->hold();
    std::vector<double> detected(fleet_.size(), 0);
    ASSERT_TRUE(pump_until(
        [&] {
          bool all = true;
          for (std::size_t i = 0; i < fleet_.size(); ++i) {
            if (detected[i] == 0 && fleet_[i].metric("drivegate_mqtt_connected") == 0) {
              detected[i] = unix_now() - from;
            }
            all = all && detected[i] != 0;
          }
          return all;
        },
        120s))
        << "a gateway never noticed its half-open link";
    pump(std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::duration<double>(
        from + static_cast<double>(half_open_.count()) - unix_now())));
    proxy_->hold_new(false);
    const double to = unix_now();
    ASSERT_TRUE(pump_until(
        [&] {
          std::size_t births = 0;
          for (const auto& m : host_->history()) births += is(m, "NBIRTH");
          return births >= births_before + fleet_.size() &&
                 std::all_of(fleet_.begin(), fleet_.end(), [](const Gateway& g) {
                   return g.metric("drivegate_mqtt_store_records") == 0;
                 });
        },
        120s))
        << "not every gateway came back from the half-open outage and replayed";
    pump(1s);
    figure("halfopen_s", to - from);
    figure("halfopen_detect_s_median", percentile(detected, 50));
    figure("halfopen_detect_s_max", percentile(detected, 100));
    // Every gateway's ramp through it, as the host can put it together, and the same span of the
    // live data before it: what goes missing there is the drive's own steps, not losses.
    const auto ms = [](double s) { return static_cast<std::uint64_t>(s * 1000); };
    const double span = to - from + 5;
    double hole = 0;
    std::size_t missing = 0;
    std::size_t missing_live = 0;
    std::size_t twice = 0;
    for (const auto& g : fleet_) {
      SCOPED_TRACE(g.id);
      const auto& h = host_->history();
      const RampSeen r = ramp_seen(h, g.id, kDrive, ms(from - 2), ms(to + 3));
      const RampSeen before = ramp_seen(h, g.id, kDrive, ms(live_from), ms(live_from + span));
      EXPECT_LT(r.worst_gap_ms, 1000) << "changes lost on the half-open link";
      hole = std::max(hole, r.worst_gap_ms);
      missing += r.missing;
      missing_live += before.missing;
      twice += r.twice;
    }
    figure("halfopen_ramp_worst_hole_ms", hole);
    figure("halfopen_speeds_missing", static_cast<double>(missing));
    figure("live_speeds_missing_same_span", static_cast<double>(missing_live));
    figure("halfopen_received_twice", static_cast<double>(twice));
    for (const auto& g : fleet_) {
      EXPECT_EQ(g.metric("drivegate_mqtt_store_replayed_total"),
                g.metric("drivegate_mqtt_store_kept_total"))
          << g.id;
    }
    ASSERT_FALSE(HasFailure());
  }

  // --- kill -9: the broker's will says which session died; the restart is the next.
  Gateway& victim = fleet_[fleet_.size() / 2];
  std::string last_bd_seq;
  for (const auto& m : node_history(victim.id)) {
    if (is(m, "NBIRTH")) last_bd_seq = bd_seq(m);
  }
  const double killed_at = unix_now();
  victim.daemon->process().stop(SIGKILL);
  ASSERT_TRUE(pump_until([&] { return count(victim.id, "NDEATH", killed_at) == 1; }, 10s))
      << "no will NDEATH for " << victim.id;
  for (const auto& m : node_history(victim.id)) {
    if (is(m, "NDEATH") && m.received_unix >= killed_at) {
      EXPECT_EQ(bd_seq(m), last_bd_seq) << "the will of another session";
    }
  }
  victim.start(broker_url(), [this] { return port(); });
  ASSERT_TRUE(pump_until([&] { return count(victim.id, "NBIRTH", killed_at) == 1; }, 20s));
  const auto h = node_history(victim.id);
  const auto reborn =
      std::find_if(h.rbegin(), h.rend(), [](const Message& m) { return is(m, "NBIRTH"); });
  EXPECT_EQ(bd_seq(*reborn), std::to_string((std::stoi(last_bd_seq) + 1) % 256));
  // Nobody else noticed: no other node died or was born again.
  pump(1s);
  for (const auto& g : fleet_) {
    if (&g == &victim) continue;
    EXPECT_EQ(count(g.id, "NDEATH", killed_at), 0u) << g.id;
    EXPECT_EQ(count(g.id, "NBIRTH", killed_at), 0u) << g.id;
  }

  // Memory of each gateway at the end (the broker's too).
  std::vector<double> rss;
  std::vector<double> hwm;
  for (const auto& g : fleet_) {
    rss.push_back(static_cast<double>(status_kb(g.daemon->process().pid(), "VmRSS")));
    hwm.push_back(static_cast<double>(status_kb(g.daemon->process().pid(), "VmHWM")));
  }
  figure("gateway_rss_kb_max", *std::max_element(rss.begin(), rss.end()));
  figure("gateway_hwm_kb_max", *std::max_element(hwm.begin(), hwm.end()));
  figure("broker_rss_kb", static_cast<double>(status_kb(broker_->pid(), "VmRSS")));
  figure("broker_hwm_kb", static_cast<double>(status_kb(broker_->pid(), "VmHWM")));
  figure("host_rss_kb", static_cast<double>(status_kb(host_->process().pid(), "VmRSS")));
  figure("test_s", unix_now() - t_start);
}

}  // namespace
}  // namespace drivegate::test
