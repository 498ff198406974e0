// The promises under attack from the MQTT side (docs/safety.md, docs/mqtt.md): the real
// drivegated on simulated nidec-washer drives, a real mosquitto and an independent Sparkplug host
// (tests/support/mqtt_e2e.h), used the way a buggy SCADA script or a hostile client on the broker
// would: retained commands, oversized ones, NaN, a run while the failsafe holds the drive, a
// rebirth storm, a STATE from the future. Asserted on what the PLC reads and the drive does.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <memory>
#include <thread>

#include "mqtt_e2e.h"

namespace drivegate::test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

class MqttAttack : public MqttE2E {
 protected:
  std::string run_at(int rpm) {
    return R"({"metrics":[{"name":"setpoint_rpm","type":"Int16","value":)" + std::to_string(rpm) +
           R"(},{"name":"command","type":"UInt16","value":1}]})";
  }
  bool stays_stopped(int unit, std::chrono::milliseconds span) {
    const auto end = std::chrono::steady_clock::now() + span;
    while (std::chrono::steady_clock::now() < end) {
      if (speed(unit) != 0 || (input(unit, reg::status) & reg::running) != 0) return false;
      std::this_thread::sleep_for(20ms);
    }
    return true;
  }
};

// A run_forward DCMD published with the retain flag is carried out once, live. Once the PLC has
// stopped the drive, neither a broker-side disconnect (another client taking the daemon's client
// id) nor a daemon restart replays it: it comes back retained and is ignored, saying why.
TEST_F(MqttAttack, ARetainedRunIsNeverReplayedAfterThePlcStopped) {
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  peer_->publish_retained(device_topic("DCMD", "washer-a"), run_at(800));
  const auto live = wait_command_result("washer-a");
  ASSERT_TRUE(live.has_value());
  EXPECT_EQ(live->second, "ok");  // live: the broker forwarded it without the flag
  ASSERT_TRUE(eventually([&] { return speed(1) == 800; }, 10s));

  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {0}), 0);  // the PLC stops it
  ASSERT_TRUE(eventually([&] { return speed(1) == 0; }, 10s));

  // The broker drops the daemon's session: someone else connects with its client id. The daemon
  // connects again, subscribes again, and is born again: the retained DCMD comes with the
  // subscription.
  {
    SparkplugPeer::Options o;
    o.client_id = std::string("drivegate-") + kEdge;
    o.stderr_file = dir_ / "thief.log";
    SparkplugPeer thief(broker_->port(), o);
  }
  wait_births();
  EXPECT_TRUE(stays_stopped(1, 3s)) << "replayed after the reconnect";
  EXPECT_TRUE(eventually(
      [&] { return daemon_log().find("retained by the broker") != std::string::npos; }, 5s))
      << "the retained DCMD did not come back at the new subscription";

  // The daemon restarts (SIGTERM, then a new process): the same.
  ASSERT_EQ(daemon_->stop(), 0);
  start_daemon("commands = true\n");
  wait_births();
  EXPECT_TRUE(stays_stopped(1, 3s)) << "replayed after the restart";
  EXPECT_TRUE(eventually(
      [&] { return daemon_log().find("retained by the broker") != std::string::npos; }, 5s));
  EXPECT_EQ(holding(1, reg::command), 0);
}

// A DCMD of 65 metrics is refused whole; NaN and infinities never reach the drive (a running
// drive keeps its speed, the heartbeat keeps its value); each is reported as the command's result.
TEST_F(MqttAttack, OversizedAndNonFiniteCommandsChangeNothing) {
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1, 900}), 0);
  ASSERT_TRUE(eventually([&] { return speed(1) == 900; }, 10s));

  std::string many;
  for (int i = 0; i < 65; ++i) {
    many += std::string(i ? "," : "") + R"({"name":"setpoint_rpm","type":"Int16","value":)" +
            std::to_string(100 + i) + "}";
  }
  dcmd("washer-a", many);
  auto r = wait_command_result("washer-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_THAT(r->second, StartsWith("refused: 65 metrics"));

  for (const char* bad : {"NaN", "Infinity", "-Infinity"}) {
    dcmd("washer-a", std::string(R"({"name":"setpoint_rpm","type":"Double","value":")") + bad +
                         "\"}");
    r = wait_command_result("washer-a");
    ASSERT_TRUE(r.has_value()) << bad;
    EXPECT_EQ(r->second, "exception 0x03 (illegal data value)") << bad;
  }
  dcmd("washer-a", R"({"name":"heartbeat","type":"Double","value":"NaN"})");
  r = wait_command_result("washer-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->second, "exception 0x03 (illegal data value)");
  EXPECT_EQ(holding(1, reg::heartbeat), 0);
  EXPECT_EQ(holding(1, reg::setpoint), 900);
  EXPECT_EQ(speed(1), 900);
  plc_->unit(1);
  EXPECT_EQ(plc_->write(reg::command, {0}), 0);
}

// 2000 rebirth requests in a burst: one rebirth at once, the rest answered by one more a few
// seconds later, and the Modbus side answers throughout.
TEST_F(MqttAttack, ARebirthStormPublishesFewBirthsAndModbusKeepsAnswering) {
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  std::atomic<bool> polling{true};
  std::size_t births_seen = 0;
  std::chrono::microseconds slowest{0};
  int failures = 0;
  std::thread plc([&] {
    Plc reader(daemon_->port());
    if (!reader.connect()) {
      ++failures;
      return;
    }
    while (polling) {
      const auto t0 = std::chrono::steady_clock::now();
      if (!reader.input(0, 11).ok()) ++failures;
      slowest = std::max(slowest, std::chrono::duration_cast<std::chrono::microseconds>(
                                      std::chrono::steady_clock::now() - t0));
      std::this_thread::sleep_for(5ms);
    }
  });
  {
    // However this block ends (a peer that cannot publish throws), the reader stops and joins.
    const std::unique_ptr<std::thread, std::function<void(std::thread*)>> joined(
        &plc, [&](std::thread* t) {
          polling = false;
          t->join();
        });
    const auto nbirths = count("NBIRTH");
    peer_->publish_repeat(
        node_topic("NCMD"),
        R"({"metrics":[{"name":"Node Control/Rebirth","type":"Boolean","value":true}]})", 2000);
    pump(8s);
    births_seen = count("NBIRTH") - nbirths;
  }
  const auto births = births_seen;
  std::cerr << births << " NBIRTHs for 2000 requests; Modbus slowest "
            << std::chrono::duration<double, std::milli>(slowest).count() << " ms\n";
  EXPECT_GE(births, 1u);
  EXPECT_LE(births, 3u);
  EXPECT_EQ(failures, 0);
  EXPECT_LT(slowest, 500ms);  // a wide margin: bench/ measures the p99 side by side
  expect_seq_consecutive(peer_->history());
}

// The primary host's STATE stamped in the far future (retained, so it comes at every subscribe)
// does not make the genuine STATE after it look stale: the births follow the genuine one.
TEST_F(MqttAttack, AStateFromTheFutureDoesNotWedgeTheSession) {
  peer_->publish_text("spBv1.0/STATE/scada", R"({"online":false,"timestamp":99999999999999})",
                      true, 1);
  start_daemon("primary_host_id = \"scada\"\n");
  ASSERT_TRUE(eventually(
      [&] { return daemon_log().find("ahead of this gateway's clock") != std::string::npos; },
      10s));
  const auto now_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  peer_->publish_text("spBv1.0/STATE/scada",
                      R"({"online":true,"timestamp":)" + std::to_string(now_ms) + "}", true, 1);
  wait_births();
}

class MqttAttackFailsafe : public MqttAttack {
 protected:
  void SetUp() override {
    if (const auto why = missing_dependency()) GTEST_SKIP() << *why;
    broker_ = std::make_unique<Broker>(dir_);
    SparkplugPeer::Options o;
    o.stderr_file = dir_ / "peer.log";
    peer_ = std::make_unique<SparkplugPeer>(broker_->port(), o);
    add_drive("washer-a", "failsafe_timeout_ms = 1000\nfailsafe_action = \"stop\"\n");
  }
};

// The PLC runs the drive and goes away: the failsafe stops it and latches. A run over MQTT is then
// refused (0x04) before the drive sees it: the drive never shows running, not even for a poll.
TEST_F(MqttAttackFailsafe, AnMqttRunCannotBumpALatchedDrive) {
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  plc_->unit(1);
  ASSERT_EQ(plc_->write(reg::command, {1, 700}), 0);
  ASSERT_TRUE(eventually([&] { return speed(1) > 0; }, 5s));
  ASSERT_TRUE(eventually([&] { return (input(1, reg::status) & kFailsafeBit) != 0; }, 5s));
  ASSERT_TRUE(eventually(
      [&] { return speed(1) == 0 && (input(1, reg::status) & reg::running) == 0; }, 15s));

  dcmd("washer-a", R"({"name":"command","type":"UInt16","value":1})");
  const auto r = wait_command_result("washer-a");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->second, "exception 0x04 (server device failure)");
  EXPECT_TRUE(stays_stopped(1, 2s));
  EXPECT_NE(input(1, reg::status) & kFailsafeBit, 0);
  EXPECT_THAT(daemon_log(), HasSubstr("only a run from the PLC clears it"));
  // The PLC's own run clears it.
  plc_->unit(1);
  EXPECT_EQ(plc_->write(reg::command, {1, 700}), 0);
  EXPECT_EQ(input(1, reg::status) & kFailsafeBit, 0);
  EXPECT_EQ(holding(1, reg::command), 1);
  plc_->unit(1);
  EXPECT_EQ(plc_->write(reg::command, {0}), 0);
}

}  // namespace
}  // namespace drivegate::test
