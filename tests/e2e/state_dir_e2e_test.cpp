// The state directory end to end (docs/security.md, "The state directory"): the real drivegated
// with store and forward on simulated drives of the tests' own (test-drive), a real mosquitto and
// the independent Sparkplug host (tests/support/mqtt_e2e.h). Whatever the directory holds instead
// of the files the daemon keeps there (FIFOs where it writes), or if it is deleted while the daemon
// runs, Modbus and HTTP go on being answered and the changes kept during an outage reach the host.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <thread>

#include "mqtt_e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

class StateDirE2E : public MqttE2E {
 protected:
  // `mqtt_keys` go into [mqtt].
  void start(const std::string& mqtt_keys = "") {
    daemon_args_ = {"--state-dir", state_.string()};
    start_daemon(mqtt_keys + "\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port_) +
                 "\"\n");
  }
  // The primary host says it is online (Sparkplug 3.0 STATE, retained, QoS 1): a node configured
  // with primary_host_id births only after it, so the host is subscribed before the births come.
  void announce_host() {
    peer_->publish_text("spBv1.0/STATE/scada", host_state(true, ++host_timestamp_), true, 1);
  }
  // The PLC runs `unit` up to `rpm` and waits for the drive to get there.
  void ramp(int unit, int rpm) {
    plc_->unit(unit);
    ASSERT_EQ(plc_->write(reg::command, {1 /*run_forward*/, static_cast<std::uint16_t>(rpm)}), 0);
    ASSERT_TRUE(eventually([&] { return speed(unit) == rpm; }, 15s)) << speed(unit);
  }
  // A historical DDATA of `device` with speed_rpm `rpm`, as the host sees it.
  bool historical_reached(const std::string& device, int rpm) {
    return peer_
        ->wait_for(
            [&](const Message& m) {
              return is(m, "DDATA", device) && m.metric("speed_rpm") != nullptr &&
                     m.metric("speed_rpm")->has_flag("historical") &&
                     m.metric("speed_rpm")->as_int() == rpm;
            },
            15s)
        .has_value();
  }
  // Modbus and HTTP both answer now (within libmodbus's timeout and http_get's).
  void expect_answering() {
    plc_->unit(1);
    const auto r = plc_->input(reg::status, 1);
    EXPECT_TRUE(r.ok()) << "Modbus not answered: " << r.exception;
    EXPECT_EQ(http_get(http_port_, "/api/v1/status").status, 200) << "HTTP not answered";
  }

  const fs::path state_ = dir_ / "state";
  const fs::path store_ = state_ / "sparkplug-plant1-gw01.store";
  const int http_port_ = free_port();
  std::uint64_t host_timestamp_ = 1700000000000;
};

// A FIFO at each name the daemon writes in the state directory: the bdSeq's temporary (written at
// every connect), the cursor's temporary (at the sync after a replay) and the first segment's
// name. Opened blocking, any of them stops the one event loop: Modbus, HTTP, polling and the
// failsafe timers. Here the session is born, an outage is kept and replayed, and both servers
// answer all along; the FIFO with a segment's name is set aside, said once in the log.
TEST_F(StateDirE2E, FifosWhereTheDaemonWritesHangNothing) {
  fs::create_directories(store_);
  for (const fs::path& f : {state_ / "sparkplug-plant1-gw01.bdseq.tmp", store_ / "cursor.tmp",
                            store_ / "0000000000000001.seg"}) {
    ASSERT_EQ(::mkfifo(f.c_str(), 0600), 0) << f;
  }
  // With a primary host: the births after the outage wait for the host to be back and
  // subscribed, whichever of it and the daemon reconnects first.
  announce_host();
  start("primary_host_id = \"scada\"\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  expect_answering();
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(state_ / "sparkplug-plant1-gw01.bdseq")));

  broker_->stop();
  ASSERT_TRUE(eventually([&] { return metric(http_port_, "drivegate_mqtt_connected") == 0; }, 5s));
  ramp(1, 900);
  std::this_thread::sleep_for(300ms);
  const double kept = metric(http_port_, "drivegate_mqtt_store_kept_total");
  EXPECT_GE(kept, 3) << "the ramp was not kept";
  EXPECT_EQ(metric(http_port_, "drivegate_mqtt_store_refused_total"), 0);
  expect_answering();

  broker_->start();
  ASSERT_TRUE(peer_->wait_for([](const Message& m) { return m.kind == "reconnected"; }, 5s));
  announce_host();  // the broker kept no retained STATE over its restart
  wait_births(15s);
  EXPECT_TRUE(historical_reached("drive-a", 900)) << "the kept ramp was not sent";
  ASSERT_TRUE(
      eventually([&] { return metric(http_port_, "drivegate_mqtt_store_records") == 0; }, 10s));
  std::this_thread::sleep_for(1500ms);  // past a sync: the cursor written
  expect_answering();
  EXPECT_EQ(metric(http_port_, "drivegate_mqtt_store_replayed_total"), kept);
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(store_ / "cursor")));
  EXPECT_TRUE(fs::is_fifo(store_ / "0000000000000001.seg.bad"));
  EXPECT_EQ(occurrences(daemon_log(), "set aside as 0000000000000001.seg.bad"), 1u) << daemon_log();
}

// The state directory deleted while the daemon runs, in a broker outage (rm -r by hand): the next
// sync makes it again, with what the store still had open carried over, so that the changes kept
// before and after the deletion are on disk and reach the host after a restart, instead of being
// written into a file nobody can open. Said once in the log, not once per replay tick.
TEST_F(StateDirE2E, ADeletedStateDirectoryIsMadeAgainAndNothingKeptIsLost) {
  fs::create_directories(state_);
  start();
  wait_births();
  ASSERT_FALSE(HasFailure());
  broker_->stop();
  ASSERT_TRUE(eventually([&] { return metric(http_port_, "drivegate_mqtt_connected") == 0; }, 5s));
  ramp(1, 900);
  fs::remove_all(state_);
  ramp(2, 600);
  std::this_thread::sleep_for(1500ms);  // past a sync
  expect_answering();
  EXPECT_TRUE(fs::is_directory(store_)) << "not made again";
  EXPECT_EQ(metric(http_port_, "drivegate_mqtt_store_refused_total"), 0);
  EXPECT_EQ(metric(http_port_, "drivegate_mqtt_store_dropped_total"), 0);
  std::this_thread::sleep_for(1500ms);
  const std::string log = daemon_log();
  EXPECT_EQ(occurrences(log, "made again"), 1u) << log;
  for (const char* error : {"cannot keep", "cannot sync", "cannot read the changes"}) {
    EXPECT_EQ(occurrences(log, error), 0u) << log;
  }
  EXPECT_EQ(daemon_->stop(), 0);

  broker_->start();
  ASSERT_TRUE(peer_->wait_for([](const Message& m) { return m.kind == "reconnected"; }, 5s));
  start();
  wait_births(15s);
  ASSERT_FALSE(HasFailure());
  EXPECT_TRUE(historical_reached("drive-a", 900)) << "kept before the deletion: lost";
  EXPECT_TRUE(historical_reached("drive-b", 600)) << "kept after the deletion: lost";
  ASSERT_TRUE(
      eventually([&] { return metric(http_port_, "drivegate_mqtt_store_records") == 0; }, 10s));
  EXPECT_EQ(metric(http_port_, "drivegate_mqtt_store_dropped_total"), 0);
  expect_seq_consecutive(peer_->history());
}

}  // namespace
}  // namespace drivegate::test
