// MQTT Sparkplug B 3.0 northbound end to end: the real drivegated
// on simulated drives of the tests' own (`drivegate sim test-drive` on ptys), a real mosquitto
// broker on loopback (tests/support/mosquitto.h) and an independent Sparkplug host:
// tests/mqtt/peer/sparkplug_peer.js, Eclipse Tahu's schema and encoder from npm over MQTT.js
// (tests/support/sparkplug_peer.h). Nothing here decodes a payload with drivegate's own code.
//
// Each test starts its own broker, peer, simulators and daemon (tests/support/mqtt_e2e.h).
#include "mqtt_e2e.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <thread>

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;
namespace fs = std::filesystem;

// --- 1. births and data ------------------------------------------------------------------------

TEST_F(MqttE2E, BirthsThenDataByExceptionWithConsecutiveSeq) {
  start_daemon();
  const Births b = wait_births();
  ASSERT_FALSE(HasFailure());

  // NBIRTH: seq 0, bdSeq 0 for the first connection, Rebirth false, a version.
  EXPECT_EQ(b.node.topic, node_topic("NBIRTH"));
  EXPECT_EQ(b.node.seq, 0u);
  ASSERT_NE(b.node.metric("bdSeq"), nullptr) << describe(b.node);
  EXPECT_EQ(b.node.metric("bdSeq")->type, "UInt64");
  EXPECT_EQ(b.node.metric("bdSeq")->value, "0");
  ASSERT_NE(b.node.metric("Node Control/Rebirth"), nullptr) << describe(b.node);
  EXPECT_EQ(b.node.metric("Node Control/Rebirth")->type, "Boolean");
  EXPECT_EQ(b.node.metric("Node Control/Rebirth")->value, "false");
  ASSERT_NE(b.node.metric("Node Info/Version"), nullptr) << describe(b.node);
  EXPECT_EQ(b.node.metric("Node Info/Version")->type, "String");
  EXPECT_FALSE(b.node.metric("Node Info/Version")->value.empty());
  EXPECT_FALSE(b.node.retain);

  // A DBIRTH per drive, seq 1 and 2 in the order they came.
  std::set<std::uint64_t> seqs;
  for (const auto& [name, m] : b.devices) {
    SCOPED_TRACE(name);
    EXPECT_EQ(m.topic, device_topic("DBIRTH", name));
    ASSERT_TRUE(m.seq.has_value());
    seqs.insert(*m.seq);
    const Metric* speed = m.metric("speed_rpm");
    ASSERT_NE(speed, nullptr) << describe(m);
    EXPECT_EQ(speed->type, "Int16");
    EXPECT_EQ(speed->properties.count("engUnit") ? speed->properties.at("engUnit") : "", "rpm");
    EXPECT_EQ(speed->value, "0");
    for (const auto& [metric, type] :
         std::vector<std::pair<std::string, std::string>>{{"status", "UInt16"},
                                                          {"fault_code", "UInt16"},
                                                          {"setpoint_rpm", "Int16"},
                                                          {"command", "UInt16"},
                                                          {"frames_good", "Int64"},
                                                          {"status_online", "Boolean"},
                                                          {"status_running", "Boolean"},
                                                          {"fault_mask", "Int64"},
                                                          {"accel_time", "Double"}}) {
      const Metric* x = m.metric(metric);
      ASSERT_NE(x, nullptr) << metric << " missing: " << describe(m);
      EXPECT_EQ(x->type, type) << metric;
    }
    EXPECT_EQ(m.metric("status_online")->value, "true");
    EXPECT_EQ(m.metric("fault_code")->value, "0");
    // A scaled adapter point goes out in engineering units: accel_time 15 x 0.1 s.
    EXPECT_EQ(m.metric("accel_time")->value, "1.5");
    EXPECT_EQ(m.metric("accel_time")->properties.count("engUnit")
                  ? m.metric("accel_time")->properties.at("engUnit")
                  : "",
              "s");
    EXPECT_EQ(m.metric("data_age_ms"), nullptr) << "data_age_ms is not published";
    // commands = false (the default): nothing is writable from MQTT.
    EXPECT_EQ(m.metric("setpoint_rpm")->properties.at("readOnly"), "true");
    EXPECT_EQ(m.metric("Command/Last Result"), nullptr);
  }
  EXPECT_EQ(seqs, (std::set<std::uint64_t>{1, 2}));

  // A PLC runs drive-a: DDATA speed_rpm follows the drive up to what the PLC reads.
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1 /*run_forward*/, 800}), 0);
  ASSERT_TRUE(eventually([&] { return speed(1) == 800; }, 10s)) << speed(1);
  std::this_thread::sleep_for(300ms);  // settled: held past min_interval
  const int settled = speed(1);
  std::vector<std::int64_t> speeds;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (std::chrono::steady_clock::now() < deadline &&
         (speeds.empty() || speeds.back() != settled)) {
    const auto m = wait("DDATA", "drive-a", 1s);
    if (m && m->metric("speed_rpm") != nullptr) speeds.push_back(m->metric("speed_rpm")->as_int());
  }
  pump(500ms);  // nothing more: the drive is steady
  speeds.clear();
  for (const auto& m : peer_->history()) {
    if (is(m, "DDATA", "drive-a") && m.metric("speed_rpm") != nullptr) {
      speeds.push_back(m.metric("speed_rpm")->as_int());
    }
  }
  ASSERT_GE(speeds.size(), 2u) << "the ramp was not reported";
  EXPECT_EQ(speeds.back(), settled);
  EXPECT_TRUE(std::is_sorted(speeds.begin(), speeds.end())) << ::testing::PrintToString(speeds);
  EXPECT_EQ(std::set<std::int64_t>(speeds.begin(), speeds.end()).size(), speeds.size())
      << "DDATA repeated an unchanged speed: " << ::testing::PrintToString(speeds);

  // Every DDATA metric is named, was in its device's DBIRTH, with the same datatype.
  for (const auto& m : peer_->history()) {
    if (!is(m, "DDATA")) continue;
    ASSERT_TRUE(b.devices.contains(m.device())) << describe(m);
    const Message& birth = b.devices.at(m.device());
    EXPECT_FALSE(m.metrics.empty()) << describe(m);
    for (const auto& x : m.metrics) {
      EXPECT_FALSE(x.from_birth_name()) << "sent without its name: " << describe(m);
      const Metric* born = birth.metric(x.name);
      ASSERT_NE(born, nullptr) << x.name << " not in the DBIRTH of " << m.device();
      EXPECT_EQ(x.type, born->type) << x.name;
    }
  }
  // At most one DDATA per device per min_interval (100 ms), by the payloads' own timestamps;
  // counters (frames_good...) not before counter_interval (10 s: not in this test).
  std::optional<std::uint64_t> previous;
  for (const auto& m : peer_->history()) {
    if (!is(m, "DDATA", "drive-a")) continue;
    ASSERT_TRUE(m.timestamp.has_value());
    if (previous) {
      EXPECT_GE(*m.timestamp, *previous + 95) << describe(m);
    }
    previous = m.timestamp;
    EXPECT_EQ(m.metric("frames_good"), nullptr) << describe(m);
    EXPECT_EQ(m.metric("bus_exchanges"), nullptr) << describe(m);
  }
  // The running bit came with it.
  bool running = false;
  for (const auto& m : peer_->history()) {
    if (is(m, "DDATA", "drive-a") && m.metric("status_running") != nullptr) {
      running = m.metric("status_running")->value == "true";
    }
  }
  EXPECT_TRUE(running);
  expect_seq_consecutive(peer_->history());

  // A clean stop: NDEATH with the bdSeq of the NBIRTH (the will is dropped: only one).
  EXPECT_EQ(daemon_->stop(), 0);
  const auto death = wait("NDEATH", {}, 5s);
  ASSERT_TRUE(death.has_value());
  ASSERT_NE(death->metric("bdSeq"), nullptr) << describe(*death);
  EXPECT_EQ(death->metric("bdSeq")->type, "UInt64");
  EXPECT_EQ(death->metric("bdSeq")->value, b.node.metric("bdSeq")->value);
  pump(500ms);
  EXPECT_EQ(count("NDEATH"), 1u);
}

TEST_F(MqttE2E, DeadbandAndCounterIntervalHoldBackDdata) {
  start_daemon("deadband = { speed_rpm = 100 }\ncounter_interval_ms = 1000\n");
  const Births b = wait_births();
  ASSERT_FALSE(HasFailure());
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1 /*run_forward*/, 800}), 0);
  ASSERT_TRUE(eventually([&] { return speed(1) == 800; }, 10s)) << speed(1);
  pump(2500ms);
  std::vector<std::int64_t> speeds{0};  // the DBIRTH's
  std::vector<std::uint64_t> counted;   // timestamps of DDATA with frames_good
  for (const auto& m : peer_->history()) {
    if (!is(m, "DDATA", "drive-a")) continue;
    if (const Metric* s = m.metric("speed_rpm")) speeds.push_back(s->as_int());
    if (const Metric* f = m.metric("frames_good")) {
      EXPECT_EQ(f->type, "Int64");
      counted.push_back(*m.timestamp);
    }
  }
  ASSERT_GE(speeds.size(), 5u) << ::testing::PrintToString(speeds);
  for (std::size_t i = 1; i < speeds.size(); ++i) {
    EXPECT_GE(std::abs(speeds[i] - speeds[i - 1]), 100) << ::testing::PrintToString(speeds);
  }
  // The counters came, about once a second, not with every poll.
  ASSERT_GE(counted.size(), 2u);
  for (std::size_t i = 1; i < counted.size(); ++i) EXPECT_GE(counted[i] - counted[i - 1], 950u);
  expect_seq_consecutive(peer_->history());
}

// --- 2. a device lost and back -----------------------------------------------------------------

TEST_F(MqttE2E, CommLostDeviceGetsDdeathAndADbirthWhenBack) {
  start_daemon();
  wait_births();
  ASSERT_FALSE(HasFailure());
  // Hold the dying pty's slave open until the new simulator is up: otherwise its number may be
  // reused by any other process's pty (a shared machine), which the stale link would then lead
  // the daemon's reopen to, off this test's line.
  const int hold =
      ::open(drive("drive-b").link.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  ASSERT_GE(hold, 0);
  const auto lost_at = std::chrono::steady_clock::now();
  drive("drive-b").sim->process().stop(SIGKILL);
  const auto death = wait("DDEATH", "drive-b", 15s);
  ASSERT_TRUE(death.has_value());
  std::cerr << "DDEATH "
            << std::chrono::duration_cast<std::chrono::milliseconds>(
                   std::chrono::steady_clock::now() - lost_at)
                   .count()
            << " ms after the sim was killed\n";
  EXPECT_TRUE(death->metrics.empty()) << describe(*death);
  EXPECT_TRUE(death->seq.has_value());
  EXPECT_EQ(input(2, reg::status) & reg::comm_lost, reg::comm_lost);
  EXPECT_EQ(count("DDEATH", "drive-a"), 0u);

  // drive-a still reports.
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1, 600}), 0);
  const auto data = peer_->wait_for(
      [](const Message& m) {
        return is(m, "DDATA", "drive-a") && m.metric("speed_rpm") != nullptr &&
               m.metric("speed_rpm")->as_int() == 600;
      },
      10s);
  EXPECT_TRUE(data.has_value()) << "drive-a's DDATA stopped with drive-b";

  // A drive answering again on the same line: DBIRTH.
  drive("drive-b").sim = std::make_unique<Sim>("test-drive", drive("drive-b").link);
  ::close(hold);
  const auto back_at = std::chrono::steady_clock::now();
  const auto birth = wait("DBIRTH", "drive-b", 15s);
  ASSERT_TRUE(birth.has_value()) << "no DBIRTH after the drive came back";
  std::cerr << "DBIRTH "
            << std::chrono::duration_cast<std::chrono::milliseconds>(
                   std::chrono::steady_clock::now() - back_at)
                   .count()
            << " ms after the sim was started again\n";
  ASSERT_NE(birth->metric("status_online"), nullptr);
  EXPECT_EQ(birth->metric("status_online")->value, "true");
  EXPECT_EQ(birth->metric("status_comm_lost")->value, "false");
  EXPECT_EQ(count("DDEATH", "drive-a"), 0u);
  EXPECT_EQ(count("DBIRTH", "drive-a"), 1u);
  EXPECT_EQ(count("NBIRTH"), 1u) << "a device coming back is no node rebirth";
  expect_seq_consecutive(peer_->history());
}

// --- 3. kill -9: the broker publishes the will ------------------------------------------------

TEST_F(MqttE2E, KilledDaemonLeavesTheWillNdeathWithTheBirthBdSeq) {
  start_daemon();
  const Births b = wait_births();
  ASSERT_FALSE(HasFailure());
  ASSERT_NE(b.node.metric("bdSeq"), nullptr);
  EXPECT_EQ(count("NDEATH"), 0u);
  daemon_->process().stop(SIGKILL);
  const auto death = wait("NDEATH", {}, 10s);
  ASSERT_TRUE(death.has_value()) << "the broker did not publish the will";
  EXPECT_EQ(death->topic, node_topic("NDEATH"));
  ASSERT_NE(death->metric("bdSeq"), nullptr) << describe(*death);
  EXPECT_EQ(death->metric("bdSeq")->type, "UInt64");
  EXPECT_EQ(death->metric("bdSeq")->value, b.node.metric("bdSeq")->value);
  // The broker saw the connection die, not a DISCONNECT.
  EXPECT_TRUE(eventually(
      [&] {
        return broker_log().find("drivegate-gw01 closed its connection") != std::string::npos;
      },
      2s))
      << broker_log();
}

// --- 3b. the bdSeq across restarts -----------------------------------------------

// The bdSeq kept in the state directory: a killed gateway's will and its next birth, a clean
// stop's NDEATH and the next birth, a file that holds no bdSeq.
TEST_F(MqttE2E, RestartsGoOnFromTheBdSeqKeptInTheStateDirectory) {
  const fs::path state = dir_ / "state";
  fs::create_directories(state);
  daemon_args_ = {"--state-dir", state.string()};
  const fs::path file = state / "sparkplug-plant1-gw01.bdseq";
  const auto bd_seq_of = [](const Message& m) {
    return m.metric("bdSeq") != nullptr ? m.metric("bdSeq")->value : "none";
  };

  start_daemon();
  Births b = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(bd_seq_of(b.node), "0") << "the first start of this edge node";
  EXPECT_EQ(slurp(file), "0\n");

  // kill -9: the broker's will carries the birth's bdSeq; the next start the one after it.
  daemon_->process().stop(SIGKILL);
  auto death = wait("NDEATH", {}, 10s);
  ASSERT_TRUE(death.has_value()) << "no will";
  EXPECT_EQ(bd_seq_of(*death), "0");
  start_daemon();
  b = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(bd_seq_of(b.node), "1");
  EXPECT_EQ(slurp(file), "1\n");
  EXPECT_THAT(daemon_log(), HasSubstr("the last session's bdSeq was 0"));

  // A clean stop: its own NDEATH with the session's bdSeq, then the next.
  EXPECT_EQ(daemon_->stop(), 0);
  death = wait("NDEATH", {}, 10s);
  ASSERT_TRUE(death.has_value()) << "no NDEATH at SIGTERM";
  EXPECT_EQ(bd_seq_of(*death), "1");
  start_daemon();
  b = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(bd_seq_of(b.node), "2");

  // A file that holds no bdSeq: said in the log, and the session starts at 0.
  EXPECT_EQ(daemon_->stop(), 0);
  ASSERT_TRUE(wait("NDEATH", {}, 10s).has_value());
  std::ofstream(file) << "garbage\n";
  start_daemon();
  b = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(bd_seq_of(b.node), "0");
  EXPECT_THAT(daemon_log(), HasSubstr(file.string() + ": not a bdSeq"));
  EXPECT_EQ(slurp(file), "0\n");
  expect_seq_consecutive(peer_->history());
}

// --- 4. rebirth on request ---------------------------------------------------------------------

TEST_F(MqttE2E, NcmdRebirthRepublishesEveryBirthInTheSameSession) {
  start_daemon();
  const Births first = wait_births();
  ASSERT_FALSE(HasFailure());
  pump(300ms);
  peer_->publish(node_topic("NCMD"),
                 R"({"metrics":[{"name":"Node Control/Rebirth","type":"Boolean","value":true}]})");
  const Births again = wait_births(5s);
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(again.node.seq, 0u);
  EXPECT_EQ(again.node.metric("bdSeq")->value, first.node.metric("bdSeq")->value)
      << "a rebirth is not a new session";
  EXPECT_EQ(again.node.metric("Node Control/Rebirth")->value, "false");
  for (const auto& [name, m] : again.devices) {
    EXPECT_EQ(m.metrics.size(), first.devices.at(name).metrics.size()) << name;
    EXPECT_EQ(m.metric("status_online")->value, "true") << name;
  }
  std::set<std::uint64_t> seqs;
  for (const auto& [name, m] : again.devices) seqs.insert(*m.seq);
  EXPECT_EQ(seqs, (std::set<std::uint64_t>{1, 2}));
  EXPECT_EQ(count("NDEATH"), 0u);
  EXPECT_EQ(sessions(), 1) << "no reconnect for a rebirth:\n" << broker_->log();
  // A Rebirth = false is not a request.
  peer_->publish(node_topic("NCMD"),
                 R"({"metrics":[{"name":"Node Control/Rebirth","type":"Boolean","value":false}]})");
  pump(1s);
  EXPECT_EQ(count("NBIRTH"), 2u);
  expect_seq_consecutive(peer_->history());
}

// --- 5. DCMD -----------------------------------------------------------------------------------

TEST_F(MqttE2E, DcmdSetpointReachesTheDriveThroughTheModbusWritePath) {
  start_daemon("commands = true\n");
  const Births b = wait_births();
  ASSERT_FALSE(HasFailure());
  const Message& birth = b.devices.at("drive-a");
  EXPECT_EQ(birth.metric("setpoint_rpm")->properties.at("readOnly"), "false");
  EXPECT_EQ(birth.metric("command")->properties.at("readOnly"), "false");
  EXPECT_EQ(birth.metric("speed_rpm")->properties.at("readOnly"), "true");
  ASSERT_NE(birth.metric("Command/Last Result"), nullptr) << describe(birth);
  EXPECT_EQ(birth.metric("Command/Last Result")->type, "String");
  ASSERT_NE(birth.metric("Command/Last Point"), nullptr);

  // setpoint + run: the PLC sees both registers and the drive speeding up.
  dcmd("drive-a", R"({"name":"setpoint_rpm","type":"Int16","value":800},)"
                  R"({"name":"command","type":"UInt16","value":1})");
  auto r = wait_command_result("drive-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->first, "setpoint_rpm,command");
  EXPECT_EQ(r->second, "ok");
  EXPECT_EQ(holding(1, reg::setpoint), 800);
  EXPECT_EQ(holding(1, reg::command), 1);
  EXPECT_THAT(drive("drive-a").sim->control("state"), HasSubstr(" target=800 "));
  ASSERT_TRUE(eventually([&] { return speed(1) == 800; }, 10s)) << speed(1);
  EXPECT_EQ(input(1, reg::status) & reg::running, reg::running);
  EXPECT_EQ(speed(2), 0) << "the other drive was moved";

  // An adapter setting beyond access = operate: the Modbus exception, nothing written.
  const std::uint16_t accel = holding(1, kAccelTime);
  dcmd("drive-a", R"({"name":"accel_time","type":"Double","value":5.5})");
  r = wait_command_result("drive-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->first, "accel_time");
  EXPECT_EQ(r->second, "exception 0x01 (illegal function)");
  EXPECT_EQ(holding(1, kAccelTime), accel);

  // A read-only metric and an unknown one: refused before the drive.
  dcmd("drive-a", R"({"name":"speed_rpm","type":"Int16","value":100})");
  r = wait_command_result("drive-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->first, "speed_rpm");
  EXPECT_THAT(r->second, StartsWith("refused"));
  dcmd("drive-a", R"({"name":"no_such_point","type":"UInt16","value":1})");
  r = wait_command_result("drive-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_THAT(r->second, StartsWith("refused"));
  dcmd("drive-a", R"({"name":"setpoint_rpm","type":"String","value":"fast"})");
  r = wait_command_result("drive-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_THAT(r->second, StartsWith("refused"));
  EXPECT_EQ(holding(1, reg::setpoint), 800);
  EXPECT_EQ(speed(1), 800);

  // Stop over MQTT too.
  dcmd("drive-a", R"({"name":"command","type":"UInt16","value":0})");
  r = wait_command_result("drive-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->second, "ok");
  EXPECT_TRUE(eventually([&] { return speed(1) == 0; }, 10s)) << speed(1);
  expect_seq_consecutive(peer_->history());

  // Each DCMD is one audit record, as MQTT's, those refused before the drive's write path too (the
  // daemon's stderr is its journal's stand-in here: docs/audit.md).
  const std::string log = daemon_log();
  EXPECT_EQ(occurrences(log, "write to drive-a (unit 1) from mqtt "), 6u) << log;
  EXPECT_THAT(log, HasSubstr(": setpoint_rpm=800 command=run_forward: ok, "));
  EXPECT_THAT(log, HasSubstr(": accel_time=5.5: denied (beyond access operate)"));
  EXPECT_THAT(log, HasSubstr(": speed_rpm=100: no such point ('speed_rpm' is read-only)"));
  EXPECT_THAT(log, HasSubstr(": no_such_point=1: no such point (no metric 'no_such_point')"));
  EXPECT_THAT(log,
              HasSubstr(": setpoint_rpm=\"fast\": invalid value ('setpoint_rpm' needs a number "
                        "or a boolean)"));
  EXPECT_THAT(log, HasSubstr(": command=stop: ok, "));
}

// A DCMD refused before it reached a drive is in the audit trail as any refused write is: a run
// the broker kept (spec 6.4: commands are published with retain false) and a command for a device
// this gateway does not have. Neither moves anything.
TEST_F(MqttE2E, DcmdsRefusedBeforeAnyDriveAreInTheAuditTrail) {
  peer_->publish_retained(device_topic("DCMD", "drive-a"),
                          R"({"metrics":[{"name":"setpoint_rpm","type":"Int16","value":800},)"
                          R"({"name":"command","type":"UInt16","value":1}]})");
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  const std::string retained =
      "write to drive-a (unit 1) from mqtt drivegate-" + std::string(kEdge) + " on " +
      broker_->url() +
      ": setpoint_rpm=800 command=1: refused (retained by the broker: a command is carried out "
      "only when it is live";
  EXPECT_TRUE(eventually([&] { return daemon_log().find(retained) != std::string::npos; }, 5s))
      << daemon_log();
  dcmd("washer-b2", R"({"name":"command","type":"UInt16","value":1})");
  EXPECT_TRUE(eventually(
      [&] {
        return daemon_log().find("write to an unknown device from mqtt drivegate-") !=
               std::string::npos;
      },
      5s))
      << daemon_log();
  EXPECT_THAT(daemon_log(), HasSubstr(": command=1: no such device (no device named 'washer-b2')"));
  pump(1s);
  EXPECT_EQ(holding(1, reg::command), 0);
  EXPECT_EQ(holding(1, reg::setpoint), 0);
  EXPECT_EQ(speed(1), 0);
  EXPECT_EQ(speed(2), 0);
  EXPECT_THAT(drive("drive-a").sim->control("state"), HasSubstr(" target=0 "));
}

TEST_F(MqttE2E, DcmdChangesNothingWhileCommandsAreOff) {
  start_daemon();  // commands = false by default
  const Births b = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(b.devices.at("drive-a").metric("Command/Last Result"), nullptr);
  dcmd("drive-a", R"({"name":"setpoint_rpm","type":"Int16","value":800},)"
                  R"({"name":"command","type":"UInt16","value":1})");
  EXPECT_TRUE(
      eventually([&] { return daemon_log().find("commands = false") != std::string::npos; }, 5s))
      << "no log line about the ignored DCMD";
  EXPECT_THAT(daemon_log(), HasSubstr("write to drive-a (unit 1) from mqtt drivegate-"));
  EXPECT_THAT(daemon_log(),
              HasSubstr(": setpoint_rpm=800 command=1: denied ([mqtt] commands = false)"));
  pump(1500ms);
  EXPECT_EQ(holding(1, reg::setpoint), 0);
  EXPECT_EQ(holding(1, reg::command), 0);
  EXPECT_EQ(speed(1), 0);
  EXPECT_THAT(drive("drive-a").sim->control("state"), HasSubstr(" target=0 "));
  for (const auto& m : peer_->history()) {
    EXPECT_EQ(m.metric("Command/Last Result"), nullptr) << describe(m);
  }
}

// --- 6. the PLC-loss failsafe is the PLC's ------------------------------------------------------

class MqttE2EFailsafe : public MqttE2E {
 protected:
  void SetUp() override {
    if (const auto why = missing_dependency()) GTEST_SKIP() << *why;
    started_ = std::chrono::steady_clock::now();
    broker_ = std::make_unique<Broker>(dir_);
    SparkplugPeer::Options o;
    o.stderr_file = dir_ / "peer.log";
    peer_ = std::make_unique<SparkplugPeer>(broker_->port(), o);
    add_drive("drive-a", "failsafe_timeout_ms = 1000\nfailsafe_action = \"stop\"\n");
  }
  // A PLC runs the drive (arming the failsafe) and goes away; DCMD heartbeats keep coming every
  // 250 ms for `span`. Returns when the failsafe bit came, or nullopt.
  std::optional<std::chrono::milliseconds> plc_leaves_mqtt_beats(std::chrono::milliseconds span) {
    {
      Plc plc(daemon_->port());
      EXPECT_TRUE(plc.connect());
      EXPECT_EQ(plc.write(reg::command, {1 /*run_forward*/, 800}), 0);
    }
    const auto left = std::chrono::steady_clock::now();
    std::uint16_t beat = 0;
    while (std::chrono::steady_clock::now() - left < span) {
      dcmd("drive-a",
           R"({"name":"heartbeat","type":"UInt16","value":)" + std::to_string(++beat) + "}");
      if ((input(1, reg::status) & kFailsafeBit) != 0) {
        return std::chrono::duration_cast<std::chrono::milliseconds>(
            std::chrono::steady_clock::now() - left);
      }
      std::this_thread::sleep_for(250ms);
    }
    return std::nullopt;
  }
};

TEST_F(MqttE2EFailsafe, DcmdHeartbeatsDoNotFeedThePlcFailsafe) {
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  const auto tripped = plc_leaves_mqtt_beats(4s);
  ASSERT_TRUE(tripped.has_value()) << "the failsafe never tripped while DCMD heartbeats came";
  std::cerr << "failsafe tripped " << tripped->count() << " ms after the PLC left\n";
  EXPECT_GE(*tripped, 900ms);
  EXPECT_TRUE(eventually(
      [&] {
        return drive("drive-a").sim->control("state").find(" target=0 ") != std::string::npos;
      },
      5s));
  // The heartbeats were written all the same (and reported ok).
  const auto r = wait_command_result("drive-a", 2s);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->second, "ok");
  EXPECT_GT(holding(1, reg::heartbeat), 0);
  // The DDATA said so too.
  EXPECT_TRUE(eventually(
      [&] {
        pump(100ms);
        for (const auto& m : peer_->history()) {
          if (is(m, "DDATA", "drive-a") && m.metric("status_failsafe") != nullptr &&
              m.metric("status_failsafe")->value == "true") {
            return true;
          }
        }
        return false;
      },
      3s));
}

TEST_F(MqttE2EFailsafe, WithFeedFailsafeDcmdHeartbeatsKeepTheDriveRunning) {
  start_daemon("commands = true\nfeed_failsafe = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  const auto tripped = plc_leaves_mqtt_beats(3s);
  EXPECT_FALSE(tripped.has_value()) << "tripped after " << tripped->count() << " ms";
  EXPECT_EQ(input(1, reg::status) & kFailsafeBit, 0);
  EXPECT_THAT(drive("drive-a").sim->control("state"), Not(HasSubstr(" target=0 ")));
  // The heartbeats stop: it trips.
  EXPECT_TRUE(eventually([&] { return (input(1, reg::status) & kFailsafeBit) != 0; }, 3s));
}

// A drive started and kept alive only over MQTT, with feed_failsafe = true: the DCMDs arm and feed
// the failsafe like a PLC's writes, and their silence trips it.
TEST_F(MqttE2EFailsafe, WithFeedFailsafeAnMqttOnlyDriveTripsWhenTheDcmdsStop) {
  start_daemon("commands = true\nfeed_failsafe = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  dcmd("drive-a", R"({"name":"setpoint_rpm","type":"Int16","value":800},)"
                  R"({"name":"command","type":"UInt16","value":1})");
  for (int beat = 1; beat <= 10; ++beat) {
    std::this_thread::sleep_for(250ms);
    dcmd("drive-a", R"({"name":"heartbeat","type":"UInt16","value":)" + std::to_string(beat) + "}");
    ASSERT_EQ(input(1, reg::status) & kFailsafeBit, 0) << "tripped while DCMDs came, beat " << beat;
  }
  EXPECT_GT(speed(1), 0);
  const auto silent = std::chrono::steady_clock::now();
  ASSERT_TRUE(eventually([&] { return (input(1, reg::status) & kFailsafeBit) != 0; }, 3s));
  const auto took = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::steady_clock::now() - silent);
  std::cerr << "failsafe tripped " << took.count() << " ms after the last DCMD\n";
  EXPECT_GE(took, 600ms);  // 1000 ms timeout, less the ~250 ms since that DCMD
  EXPECT_TRUE(eventually(
      [&] {
        return drive("drive-a").sim->control("state").find(" target=0 ") != std::string::npos;
      },
      5s));
}

// --- 7. broker restart --------------------------------------------------------------------------

TEST_F(MqttE2E, BrokerRestartKeepsModbusServedAndRebirthsWithANewBdSeq) {
  const int http_port = free_port();
  start_daemon("\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) + "\"\n");
  const Births first = wait_births();
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_connected"), 1);
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_online"), 1);
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_connects_total"), 1);
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_device_births_total"), 2);
  ASSERT_FALSE(HasFailure());
  const auto bd0 = first.node.metric("bdSeq")->as_uint();

  std::atomic<bool> stop{false};
  std::atomic<int> reads{0};
  std::atomic<int> failures{0};
  std::atomic<int> slowest_ms{0};
  std::thread poller([&] {
    Plc plc(daemon_->port());
    if (!plc.connect()) {
      ++failures;
      return;
    }
    int unit = 1;
    while (!stop) {
      plc.unit(unit);
      unit = 3 - unit;
      const auto t0 = std::chrono::steady_clock::now();
      const auto r = plc.input(reg::status, 1);
      const int ms = static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                          std::chrono::steady_clock::now() - t0)
                                          .count());
      if (ms > slowest_ms) slowest_ms = ms;
      ++reads;
      if (!r.ok() || (r.regs[0] & reg::online) == 0) ++failures;
      std::this_thread::sleep_for(50ms);
    }
  });

  pump(300ms);
  broker_->stop();
  // Long enough for two failed attempts (1 s, then 2 s later): the daemon's next one (4 s later)
  // comes well after the broker is back and the peer has resubscribed, so the peer cannot miss
  // the new NBIRTH.
  std::this_thread::sleep_for(4s);
  // The outage shows in the metrics, and in the status JSON with its reason.
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_connected"), 0);
  EXPECT_GE(metric(http_port, "drivegate_mqtt_connection_losses_total"), 2);
  EXPECT_THAT(http_get(http_port, "/api/v1/status").body,
              ::testing::AllOf(::testing::HasSubstr("\"session\": \"offline\""),
                               ::testing::Not(::testing::HasSubstr("\"last_error\": \"\""))));
  broker_->start();
  const auto back = peer_->wait_for([](const Message& m) { return m.kind == "reconnected"; }, 5s);
  EXPECT_TRUE(back.has_value()) << "the peer did not reconnect";
  const Births again = wait_births(15s);
  stop = true;
  poller.join();
  ASSERT_FALSE(HasFailure());
  std::cerr << reads << " Modbus reads during the outage, slowest " << slowest_ms << " ms; bdSeq "
            << bd0 << " then " << again.node.metric("bdSeq")->value << "\n";
  EXPECT_EQ(failures, 0) << "of " << reads << " reads";
  EXPECT_GT(reads, 50);
  EXPECT_EQ(again.node.seq, 0u);
  EXPECT_GT(again.node.metric("bdSeq")->as_uint(), bd0);
  EXPECT_EQ(again.node.metric("bdSeq")->type, "UInt64");
  expect_seq_consecutive(peer_->history());
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_connected"), 1);
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_connects_total"), 2);
  // One outage: one session lost, whatever attempts failed while it lasted.
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_sessions_lost_total"), 1);
  EXPECT_GE(metric(http_port, "drivegate_mqtt_connection_losses_total"), 3);
  EXPECT_THAT(http_get(http_port, "/api/v1/status").body,
              ::testing::HasSubstr("\"connects\": 2, \"losses\": "));
  EXPECT_THAT(http_get(http_port, "/api/v1/status").body,
              ::testing::HasSubstr(", \"sessions_lost\": 1, "));
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_bdseq"), again.node.metric("bdSeq")->as_uint());
}

// --- 8. the primary host's STATE ---------------------------------------------------------------

TEST_F(MqttE2E, BirthsWaitForThePrimaryHostAndEndWhenItGoesOffline) {
  start_daemon("primary_host_id = \"scada\"\n");
  pump(2s);
  EXPECT_EQ(count("NBIRTH"), 0u) << "born without the primary host";
  EXPECT_EQ(count("DBIRTH"), 0u);

  const std::uint64_t t0 =
      static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                     std::chrono::system_clock::now().time_since_epoch())
                                     .count());
  const std::string state = "spBv1.0/STATE/scada";
  peer_->publish_text(state, host_state(true, t0), true, 1);
  const Births first = wait_births(5s);
  ASSERT_FALSE(HasFailure());
  const auto bd1 = first.node.metric("bdSeq")->as_uint();

  peer_->publish_text(state, host_state(false, t0 + 1), true, 1);
  const auto death = wait("NDEATH", {}, 5s);
  ASSERT_TRUE(death.has_value()) << "no NDEATH when the primary host went offline";
  EXPECT_EQ(death->metric("bdSeq")->as_uint(), bd1);
  // Reconnected and waiting again: no birth while the retained STATE says offline.
  pump(2500ms);
  EXPECT_EQ(count("NBIRTH"), 1u);
  EXPECT_EQ(count("NDEATH"), 1u) << "the will came on top of the published NDEATH";

  peer_->publish_text(state, host_state(true, t0 + 2), true, 1);
  const Births second = wait_births(5s);
  ASSERT_FALSE(HasFailure());
  const auto bd2 = second.node.metric("bdSeq")->as_uint();
  EXPECT_EQ(bd2, (bd1 + 1) % 256) << "one new session";
  EXPECT_EQ(second.node.seq, 0u);

  // A stale offline (older timestamp) is ignored.
  peer_->publish_text(state, host_state(false, t0), true, 1);
  pump(1500ms);
  EXPECT_EQ(count("NDEATH"), 1u) << "a stale STATE offline ended the session";
  expect_seq_consecutive(peer_->history());
}

// A Sparkplug 2.2 host: STATE/<id>, the text ONLINE / OFFLINE, retained; the same
// session rules as 3.0's.
TEST_F(MqttE2E, A22PrimaryHostsOnlineAndOfflineTextRuleTheSession) {
  start_daemon("primary_host_id = \"scada\"\nprimary_host_version = \"2.2\"\n");
  // 3.0's STATE for the same host id is not the one this node listens to.
  peer_->publish_text("spBv1.0/STATE/scada", R"({"online":true,"timestamp":1})", false, 1);
  pump(1500ms);
  EXPECT_EQ(count("NBIRTH"), 0u) << "born on a 3.0 STATE while configured for 2.2";

  peer_->publish_text("STATE/scada", "ONLINE", true, 1);
  const Births first = wait_births(5s);
  ASSERT_FALSE(HasFailure());
  const auto bd1 = first.node.metric("bdSeq")->as_uint();

  peer_->publish_text("STATE/scada", "OFFLINE", true, 1);
  const auto death = wait("NDEATH", {}, 5s);
  ASSERT_TRUE(death.has_value()) << "no NDEATH when the 2.2 host went OFFLINE";
  EXPECT_EQ(death->metric("bdSeq")->as_uint(), bd1);
  pump(2500ms);  // reconnected, and the retained OFFLINE holds the births back
  EXPECT_EQ(count("NBIRTH"), 1u);

  peer_->publish_text("STATE/scada", "ONLINE", true, 1);
  const Births second = wait_births(5s);
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(second.node.metric("bdSeq")->as_uint(), (bd1 + 1) % 256);
  expect_seq_consecutive(peer_->history());
  peer_->publish_text("STATE/scada", "", true, 1);  // the retained STATE cleared
}

// --- 9. SIGHUP changing the devices -------------------------------------------------------------

TEST_F(MqttE2E, SighupAddingADeviceRebirthsWithIt) {
  start_daemon();
  const Births first = wait_births();
  ASSERT_FALSE(HasFailure());
  const auto bd = first.node.metric("bdSeq")->as_uint();
  add_drive("drive-c");
  std::ofstream(daemon_->config()) << config("");
  daemon_->process().signal(SIGHUP);
  const Births again = wait_births(15s);
  ASSERT_FALSE(HasFailure());
  EXPECT_TRUE(again.devices.contains("drive-c"));
  EXPECT_EQ(again.node.metric("bdSeq")->as_uint(), bd) << "a rebirth, not a reconnect";
  EXPECT_EQ(again.node.seq, 0u);
  ASSERT_TRUE(again.devices.contains("drive-c"));
  const Message& c = again.devices.at("drive-c");
  ASSERT_NE(c.metric("speed_rpm"), nullptr) << describe(c);
  EXPECT_EQ(c.metric("speed_rpm")->type, "Int16");
  wait_online(3);
  // It reports like the others.
  plc_->unit(3);
  ASSERT_EQ(plc_->write(reg::command, {1, 700}), 0);
  EXPECT_TRUE(peer_
                  ->wait_for(
                      [](const Message& m) {
                        return is(m, "DDATA", "drive-c") && m.metric("speed_rpm") != nullptr &&
                               m.metric("speed_rpm")->as_int() == 700;
                      },
                      10s)
                  .has_value());
  expect_seq_consecutive(peer_->history());
}

TEST_F(MqttE2E, SighupRemovingADeviceSendsItsDdeathThenRebirthsWithoutIt) {
  start_daemon();
  const Births first = wait_births();
  ASSERT_FALSE(HasFailure());
  const auto bd = first.node.metric("bdSeq")->as_uint();
  Drive gone = std::move(drives_.back());
  drives_.pop_back();
  std::ofstream(daemon_->config()) << config("");
  daemon_->process().signal(SIGHUP);
  const auto death = wait("DDEATH", "drive-b", 10s);
  ASSERT_TRUE(death.has_value()) << "no DDEATH for the device removed";
  const Births again = wait_births(10s);
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(again.node.metric("bdSeq")->as_uint(), bd);
  pump(1s);
  EXPECT_EQ(count("DBIRTH", "drive-b"), 1u) << "the removed device was born again";
  EXPECT_EQ(count("DBIRTH", "drive-a"), 2u);
  expect_seq_consecutive(peer_->history());
}

TEST_F(MqttE2E, SeqWrapsFrom255To0) {
  // Every poll changes the counters, and nothing holds them back: a DDATA per poll per drive.
  poll_ms_ = 20;
  start_daemon("min_interval_ms = 0\ncounter_interval_ms = 0\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  const auto wrapped = peer_->wait_for(
      [](const Message& m) {
        return m.kind == "msg" && m.message_type() != "NBIRTH" && m.seq == 0u;
      },
      20s);
  ASSERT_TRUE(wrapped.has_value()) << "no message with seq 0 after 255";
  pump(200ms);
  EXPECT_EQ(count("NBIRTH"), 1u);
  expect_seq_consecutive(peer_->history());
  std::size_t n = 0;
  for (const auto& m : peer_->history()) n += is(m, "DDATA") ? 1 : 0;
  EXPECT_GE(n, 254u);
}

// --- 10. SIGHUP changing [mqtt] ------------------------------------------------------

// A changed [mqtt] ends the session cleanly and begins the next without a restart: the NDEATH
// of the old session, then the births of the new with the next bdSeq; another edge node id is
// another node, with its own bdSeq; [mqtt] removed ends the session. Modbus never notices.
TEST_F(MqttE2E, SighupChangingMqttEndsTheSessionAndBeginsTheNext) {
  start_daemon();
  const Births first = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(first.node.metric("bdSeq")->value, "0");
  const auto history_size = [&] { return peer_->history().size(); };

  // min_interval and counter_interval changed: same node, a new session.
  std::size_t from = history_size();
  std::ofstream(daemon_->config()) << config("min_interval_ms = 0\ncounter_interval_ms = 0\n");
  daemon_->process().signal(SIGHUP);
  const auto death = wait("NDEATH", {}, 10s);
  ASSERT_TRUE(death.has_value()) << "no NDEATH for the session the reload ended";
  EXPECT_EQ(death->topic, node_topic("NDEATH"));
  EXPECT_EQ(death->metric("bdSeq")->value, "0");
  const Births second = wait_births(10s);
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(second.node.metric("bdSeq")->value, "1") << "the same node goes on from its bdSeq";
  EXPECT_EQ(second.node.seq, 0u);
  // In that order, and the broker saw a DISCONNECT (a clean end: no will of its own).
  std::vector<std::string> order;
  for (std::size_t i = from; i < peer_->history().size(); ++i) {
    const Message& m = peer_->history()[i];
    if (is(m, "NDEATH") || is(m, "NBIRTH")) order.push_back(m.message_type());
  }
  EXPECT_THAT(order, ::testing::ElementsAre("NDEATH", "NBIRTH"));
  EXPECT_THAT(broker_log(), HasSubstr("Client drivegate-gw01 disconnected"));
  EXPECT_THAT(daemon_log(), Not(HasSubstr("take effect at the next restart")));
  EXPECT_THAT(daemon_log(), HasSubstr("[mqtt] applied"));
  // The new settings hold: with counter_interval 0 every poll's counters go out.
  pump(1s);
  std::size_t ddata = 0;
  for (std::size_t i = from; i < peer_->history().size(); ++i) {
    ddata += is(peer_->history()[i], "DDATA", "drive-a") ? 1 : 0;
  }
  EXPECT_GE(ddata, 3u) << "counter_interval_ms = 0 not applied";

  // Another edge node id: the old node dies, the new one is born with its own first bdSeq.
  std::string toml = config("");
  const std::string id = "edge_node_id = \"gw01\"";
  ASSERT_NE(toml.find(id), std::string::npos);
  toml.replace(toml.find(id), id.size(), "edge_node_id = \"gw02\"");
  from = history_size();
  std::ofstream(daemon_->config()) << toml;
  daemon_->process().signal(SIGHUP);
  const auto old_death = wait("NDEATH", {}, 10s);
  ASSERT_TRUE(old_death.has_value());
  EXPECT_EQ(old_death->topic, node_topic("NDEATH"));
  EXPECT_EQ(old_death->metric("bdSeq")->value, "1");
  const auto born = wait("NBIRTH", {}, 10s);
  ASSERT_TRUE(born.has_value());
  EXPECT_EQ(born->topic, std::string("spBv1.0/") + kGroup + "/NBIRTH/gw02");
  EXPECT_EQ(born->metric("bdSeq")->value, "0");

  // [mqtt] removed: the session ends, the gateway serves on.
  std::string without = config("");
  without.erase(without.find("[mqtt]"));
  std::ofstream(daemon_->config()) << without;
  daemon_->process().signal(SIGHUP);
  const auto last = wait("NDEATH", {}, 10s);
  ASSERT_TRUE(last.has_value()) << "no NDEATH when [mqtt] was removed";
  EXPECT_EQ(last->topic, std::string("spBv1.0/") + kGroup + "/NDEATH/gw02");
  EXPECT_TRUE(
      eventually([&] { return daemon_log().find("[mqtt] removed") != std::string::npos; }, 5s));
  pump(1s);
  EXPECT_EQ(count("NBIRTH"), 3u) << "a session after [mqtt] was removed";
  for (int unit : {1, 2}) {
    plc_->unit(unit);
    const auto r = plc_->input(reg::status, 1);
    ASSERT_TRUE(r.ok());
    EXPECT_NE(r.regs[0] & reg::online, 0) << "unit " << unit;
  }
  EXPECT_TRUE(daemon_->process().running());
  expect_seq_consecutive(peer_->history());
}

// --- 11. several brokers --------------------------------------------------------------

// brokers = [A, B]: the session is on A; A stops, and the next attempt goes to B, with the next
// bdSeq and a full rebirth there; A back changes nothing. Modbus is served throughout.
TEST_F(MqttE2E, SeveralBrokersTheNodeWalksToTheNextWhenOneFails) {
  OtherBroker b(dir_ / "peer-b.log");
  brokers_ = {broker_->url(), b.broker.url()};
  const int http_port = free_port();
  start_daemon("\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) + "\"\n");
  const Births first = wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(first.node.metric("bdSeq")->value, "0");
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_broker_index"), 0);
  EXPECT_THAT(
      http_get(http_port, "/api/v1/status").body,
      HasSubstr("\"broker\": \"" + broker_->url() + "\", \"broker_index\": 0, \"brokers\": 2"));

  broker_->stop();
  const auto born = b.peer.wait_for([](const Message& m) { return is(m, "NBIRTH"); }, 15s);
  ASSERT_TRUE(born.has_value()) << "no NBIRTH on the second broker";
  EXPECT_EQ(born->metric("bdSeq")->value, "1");
  EXPECT_EQ(born->seq, 0u);
  // Both drives born there too (the peer's history fills as it is read).
  std::set<std::string> born_there;
  while (born_there.size() < drives_.size()) {
    const auto d = b.peer.wait_for([](const Message& m) { return is(m, "DBIRTH"); }, 5s);
    if (!d) break;
    born_there.insert(d->device());
  }
  EXPECT_EQ(born_there.size(), drives_.size());
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_broker_index"), 1);
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_broker_switches_total"), 1);
  EXPECT_THAT(http_get(http_port, "/api/v1/status").body,
              HasSubstr("\"broker\": \"" + b.broker.url() + "\", \"broker_index\": 1"));
  EXPECT_THAT(daemon_log(), HasSubstr("trying " + b.broker.url() + " next"));

  // Data flows on B: a PLC's run shows there.
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1, 650}), 0);
  EXPECT_TRUE(b.peer
                  .wait_for(
                      [](const Message& m) {
                        return is(m, "DDATA", "drive-a") && m.metric("speed_rpm") != nullptr &&
                               m.metric("speed_rpm")->as_int() == 650;
                      },
                      10s)
                  .has_value());
  // A back: the node stays where it has a session.
  const std::size_t births_on_a = count("NBIRTH");
  broker_->start();
  pump(2s);
  EXPECT_EQ(count("NBIRTH"), births_on_a) << "moved back to A while the session on B was fine";
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_broker_switches_total"), 1);
  expect_seq_consecutive(b.peer.history());
}

// brokers = [A, B] with a primary host: offline on A (its retained STATE), online on B. The node
// connects to A, reads that the host is offline there, leaves without a birth and is born on B.
// Then the host goes offline on B: NDEATH there, and the node walks on to A (where it waits).
TEST_F(MqttE2E, SeveralBrokersThePrimaryHostOfflineOnOneSendsTheNodeToTheNext) {
  OtherBroker b(dir_ / "peer-b.log");
  const auto now_ms = [] {
    return std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(
                              std::chrono::system_clock::now().time_since_epoch())
                              .count());
  };
  const std::string state = "spBv1.0/STATE/scada";
  peer_->publish_text(state, R"({"online":false,"timestamp":)" + now_ms() + "}", true, 1);
  b.peer.publish_text(state, R"({"online":true,"timestamp":)" + now_ms() + "}", true, 1);
  brokers_ = {broker_->url(), b.broker.url()};
  start_daemon("primary_host_id = \"scada\"\n");
  const auto born = b.peer.wait_for([](const Message& m) { return is(m, "NBIRTH"); }, 15s);
  ASSERT_TRUE(born.has_value()) << "not born on the broker where the host is online";
  pump(300ms);  // what A's peer has seen by now
  EXPECT_EQ(count("NBIRTH"), 0u) << "born where the host is offline";
  EXPECT_EQ(count("NDEATH"), 0u) << "an NDEATH for a session that had no birth";
  EXPECT_THAT(daemon_log(), HasSubstr("offline on " + broker_->url()));
  EXPECT_EQ(born->metric("bdSeq")->value, "1");

  b.peer.publish_text(state, R"({"online":false,"timestamp":)" + now_ms() + "}", true, 1);
  const auto death = b.peer.wait_for([](const Message& m) { return is(m, "NDEATH"); }, 10s);
  ASSERT_TRUE(death.has_value()) << "no NDEATH on B when the host went offline there";
  EXPECT_EQ(death->metric("bdSeq")->value, "1");
  // Back on A, where the host is still offline: it waits there, and then walks on again.
  EXPECT_TRUE(eventually(
      [&] {
        const std::string log = daemon_log();
        std::size_t n = 0;
        for (auto at = log.find("trying "); at != std::string::npos;
             at = log.find("trying ", at + 1)) {
          ++n;
        }
        return n >= 2;
      },
      10s))
      << daemon_log();
  pump(300ms);
  EXPECT_EQ(count("NBIRTH"), 0u);
  // Both STATEs cleared for the brokers' next users.
  peer_->publish_text(state, "", true, 1);
  b.peer.publish_text(state, "", true, 1);
}

// --- 12. store and forward ---------------------------------------------------------

// A broker outage while a drive ramps: every change the edge node saw while the broker was away
// is kept on disk and, once a session is back, published after the births as historical DDATA
// with its original time, in order, none twice; live data after it is not historical.
TEST_F(MqttE2E, ABrokerOutageLosesNoChangeTheyComeBackHistoricalInOrder) {
  // A ramp of 3 s to 900 rpm (0 to 3000 in 10 s): an outage long enough for the host to be back
  // on the broker before the edge node's next try, which then finds it there for its births.
  drive("drive-a").device_extra = "[device.options]\naccel_time_ms = 10000\n";
  const fs::path state = dir_ / "state";
  fs::create_directories(state);
  daemon_args_ = {"--state-dir", state.string()};
  const int http_port = free_port();
  start_daemon("\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) + "\"\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_store_records"), 0);

  const auto unix_ms = [] {
    return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                          std::chrono::system_clock::now().time_since_epoch())
                                          .count());
  };
  broker_->stop();
  ASSERT_TRUE(eventually([&] { return metric(http_port, "drivegate_mqtt_connected") == 0; }, 5s));
  const std::uint64_t outage_start = unix_ms();
  // The PLC runs drive-a up to 900 rpm while nobody hears MQTT.
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1 /*run_forward*/, 900}), 0);
  ASSERT_TRUE(eventually([&] { return speed(1) == 900; }, 15s)) << speed(1);
  std::this_thread::sleep_for(300ms);
  const double kept = metric(http_port, "drivegate_mqtt_store_records");
  EXPECT_GE(kept, 3) << "the ramp was not kept";
  EXPECT_GT(metric(http_port, "drivegate_mqtt_store_bytes"), 0);
  const std::uint64_t outage_end = unix_ms();

  broker_->start();
  ASSERT_TRUE(peer_->wait_for([](const Message& m) { return m.kind == "reconnected"; }, 5s));
  const Births again = wait_births(15s);
  ASSERT_FALSE(HasFailure());
  // The historical DDATA of drive-a, as the host saw them.
  ASSERT_TRUE(
      eventually([&] { return metric(http_port, "drivegate_mqtt_store_records") == 0; }, 10s))
      << "not all replayed";
  pump(500ms);
  std::vector<std::int64_t> speeds;
  std::vector<std::uint64_t> times;
  bool after_birth = false;
  bool live_after = false;
  for (const auto& m : peer_->history()) {
    if (is(m, "NBIRTH") && m.seq == 0u && m.metric("bdSeq") != nullptr &&
        m.metric("bdSeq")->value == again.node.metric("bdSeq")->value) {
      after_birth = true;
    }
    if (!is(m, "DDATA", "drive-a") || m.metric("speed_rpm") == nullptr) continue;
    const Metric& sp = *m.metric("speed_rpm");
    if (!sp.has_flag("historical")) {
      live_after = live_after || !speeds.empty();
      continue;
    }
    EXPECT_TRUE(after_birth) << "a historical DDATA before the new session's births";
    speeds.push_back(sp.as_int());
    ASSERT_TRUE(sp.timestamp.has_value());
    times.push_back(*sp.timestamp);
  }
  std::cerr << "kept " << kept
            << " changes; historical speeds: " << ::testing::PrintToString(speeds) << "\n";
  ASSERT_GE(speeds.size(), 3u) << describe(peer_->history());
  EXPECT_TRUE(std::is_sorted(speeds.begin(), speeds.end())) << "out of order";
  EXPECT_EQ(std::set<std::int64_t>(speeds.begin(), speeds.end()).size(), speeds.size())
      << "a change sent twice";
  EXPECT_EQ(speeds.back(), 900) << "the last change of the outage";
  EXPECT_TRUE(std::is_sorted(times.begin(), times.end()));
  EXPECT_GE(times.front() + 1000, outage_start) << "stamped with when the drive had the value";
  EXPECT_LE(times.back(), outage_end);
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_store_replayed_total"),
            metric(http_port, "drivegate_mqtt_store_kept_total"));
  EXPECT_EQ(metric(http_port, "drivegate_mqtt_store_dropped_total"), 0);
  expect_seq_consecutive(peer_->history());
  // And live again: a new setpoint is a plain DDATA.
  ASSERT_EQ(plc_->write(reg::setpoint, {700}), 0);
  const auto live = peer_->wait_for(
      [](const Message& m) {
        return is(m, "DDATA", "drive-a") && m.metric("speed_rpm") != nullptr &&
               m.metric("speed_rpm")->as_int() == 700;
      },
      15s);
  ASSERT_TRUE(live.has_value());
  EXPECT_FALSE(live->metric("speed_rpm")->has_flag("historical"));
}

// What was kept survives a restart of the daemon: kept during an outage, the daemon stopped, the
// broker back, the daemon started: the changes come out after its births.
TEST_F(MqttE2E, KeptChangesSurviveARestartOfTheDaemon) {
  const fs::path state = dir_ / "state";
  fs::create_directories(state);
  daemon_args_ = {"--state-dir", state.string()};
  start_daemon();
  wait_births();
  ASSERT_FALSE(HasFailure());
  broker_->stop();
  std::this_thread::sleep_for(1500ms);
  plc_->unit(2);
  ASSERT_EQ(plc_->write(reg::command, {1, 600}), 0);
  ASSERT_TRUE(eventually([&] { return speed(2) == 600; }, 15s)) << speed(2);
  std::this_thread::sleep_for(1500ms);  // past a sync
  // The stop puts the drives in their stop state: those changes are kept too.
  EXPECT_EQ(daemon_->stop(), 0);
  EXPECT_TRUE(fs::exists(state / "sparkplug-plant1-gw01.store"));
  broker_->start();
  ASSERT_TRUE(peer_->wait_for([](const Message& m) { return m.kind == "reconnected"; }, 5s));
  start_daemon();
  wait_births(15s);
  ASSERT_FALSE(HasFailure());
  EXPECT_THAT(daemon_log(), HasSubstr("changes kept from before"));
  const auto reached = peer_->wait_for(
      [](const Message& m) {
        return is(m, "DDATA", "drive-b") && m.metric("speed_rpm") != nullptr &&
               m.metric("speed_rpm")->has_flag("historical") &&
               m.metric("speed_rpm")->as_int() == 600;
      },
      10s);
  EXPECT_TRUE(reached.has_value()) << "the ramp kept before the restart was not sent";
  expect_seq_consecutive(peer_->history());
}

}  // namespace
}  // namespace drivegate::test
