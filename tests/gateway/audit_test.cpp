// Every write a device is asked for is one audit record (daemon/history/command_audit.h)
// with the right source and result: a Modbus client's (plain, TLS with a role), an MQTT DCMD's,
// the failsafe's, shutdown's; accepted, refused at once, refused by the drive, or never
// answered. And the device's events: fault raised and cleared, comm lost and back, started and
// stopped, failsafe tripped and cleared. On the real device with a fake driver and clock.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include "fake_adapter.h"
#include "gateway/device.h"

namespace drivegate {
namespace {

using namespace std::chrono_literals;
using ::testing::Contains;
using ::testing::ElementsAre;

constexpr std::uint16_t kCommand = 0, kHeartbeat = 2, kLimit = 16;

class FakeJournal final : public JournalWriter {
 public:
  void info(std::string_view, std::span<const std::string> fields) override {
    entries.emplace_back(fields.begin(), fields.end());
  }
  std::vector<std::vector<std::string>> entries;
};

Session modbus_client(AccessLevel access, std::string client = "192.0.2.7:50122") {
  return Session{access, WordOrder::big, true,
                 Source{.kind = SourceKind::modbus, .listener = "0.0.0.0:502", .client = client}};
}

Session tls_client(AccessLevel access) {
  return Session{access, WordOrder::big, true,
                 Source{.kind = SourceKind::modbus_tls,
                        .listener = "0.0.0.0:802",
                        .client = "192.0.2.9:40000",
                        .subject = "CN=plc-1",
                        .role = "operator"}};
}

class AuditTest : public ::testing::Test {
 protected:
  void SetUp() override {
    DeviceConfig cfg;
    cfg.name = "dev";
    cfg.unit_id = 7;
    cfg.failsafe.timeout = 1000ms;
    cfg.failsafe.action = FailsafeAction::stop;
    auto driver = std::make_unique<test::FakeDriver>(DeviceEnv{});
    driver->traits_.comm_timeout = 2000ms;
    driver->traits_.write_timeout = 60s;
    driver->common_.ready = true;
    fake_ = driver.get();
    device_ = std::make_unique<Device>(
        cfg, test::kFakeAdapter, std::move(driver),
        std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>()),
        t0_, &history_);
    device_->link().health.frame_good(t0_);
  }
  TimePoint at(Millis ms) const { return t0_ + ms; }
  Outcome write(const Session& s, std::uint16_t address, std::vector<std::uint16_t> v, Millis ms) {
    const Outcome r = device_->write(
        s, Table::holding, address, v, [this](Outcome o) { answers_.push_back(o); }, at(ms));
    device_->next_exchange(at(ms), Turn::write);
    return r;
  }
  void confirm(Millis ms, WriteResult r = WriteResult::ok) {
    fake_->completions.push_back({fake_->last_ticket, r});
    device_->next_exchange(at(ms), Turn::poll);
  }
  void tick(Millis ms) {
    Link& link = device_->link();
    if (link.health.lost_by(at(ms), link.policy.comm_timeout)) device_->on_comm_lost(at(ms));
    device_->on_tick(at(ms));
  }
  std::vector<Event> commands() { return history_.events().query({.kind = EventKind::command}); }
  std::vector<EventKind> kinds() {
    std::vector<EventKind> out;
    for (const Event& e : history_.events().query({})) out.push_back(e.kind);
    return out;
  }

  std::int64_t wall_ms_ = 1'700'000'000'000;
  FakeJournal journal_;
  History history_{100, [this] { return wall_ms_; }, &journal_};
  TimePoint t0_ = TimePoint{} + std::chrono::hours(1);
  test::FakeDriver* fake_ = nullptr;
  std::unique_ptr<Device> device_;
  std::vector<Outcome> answers_;
};

TEST_F(AuditTest, AConfirmedModbusWriteIsOneRecordWithItsClientAndDuration) {
  ASSERT_EQ(write(tls_client(AccessLevel::operate), kCommand, {1, 1500}, 0ms), Outcome::ok);
  EXPECT_TRUE(commands().empty());  // recorded when it settles, not before
  confirm(42ms);
  ASSERT_THAT(answers_, ElementsAre(Outcome::ok));
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].device, "dev");
  EXPECT_EQ(c[0].unit, 7);
  EXPECT_EQ(c[0].field("source"), "modbus_tls");
  EXPECT_EQ(c[0].field("client"), "192.0.2.9:40000");
  EXPECT_EQ(c[0].field("subject"), "CN=plc-1");
  EXPECT_EQ(c[0].field("role"), "operator");
  EXPECT_EQ(c[0].field("points"), "setpoint_rpm=1500 command=run_forward");
  EXPECT_EQ(c[0].field("result"), "ok");
  EXPECT_EQ(c[0].field("took_ms"), "42");
  ASSERT_EQ(journal_.entries.size(), 1u);
  EXPECT_THAT(journal_.entries[0], Contains("CLIENT=192.0.2.9:40000"));
  EXPECT_THAT(journal_.entries[0], Contains("ROLE=operator"));
  EXPECT_THAT(journal_.entries[0], Contains("RESULT=ok"));
  EXPECT_THAT(journal_.entries[0], Contains("DEVICE=dev"));
  EXPECT_THAT(journal_.entries[0], Contains("UNIT=7"));
  EXPECT_EQ(history_.audit().counts().at(SourceKind::modbus_tls, Outcome::ok), 1u);
}

TEST_F(AuditTest, WritesRefusedAtOnceAreEachOneRecordWithWhy) {
  // Beyond the session's access; an unmapped address; a value out of range; the drive refusing.
  EXPECT_EQ(write(modbus_client(AccessLevel::read), kCommand, {1}, 0ms), Outcome::denied);
  EXPECT_EQ(write(modbus_client(AccessLevel::maintain), 900, {1}, 0ms), Outcome::no_such_point);
  EXPECT_EQ(write(modbus_client(AccessLevel::maintain), kLimit, {0, 5}, 0ms),
            Outcome::invalid_value);
  fake_->refuse_command = Command::run_reverse;
  EXPECT_EQ(write(modbus_client(AccessLevel::operate), kCommand, {2}, 0ms), Outcome::refused);
  const auto c = commands();
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c[0].field("result"), "denied");
  EXPECT_EQ(c[0].field("why"), "beyond access read");
  EXPECT_EQ(c[0].field("points"), "holding 0 = 1");
  EXPECT_EQ(c[1].field("result"), "no_such_point");
  EXPECT_EQ(c[1].field("points"), "holding 900 = 1");
  EXPECT_EQ(c[2].field("result"), "invalid_value");
  EXPECT_EQ(c[3].field("result"), "refused");
  EXPECT_EQ(c[3].field("points"), "command=run_reverse");
  for (const Event& e : c) {
    EXPECT_EQ(e.field("source"), "modbus");
    EXPECT_EQ(e.field("took_ms"), "");  // answered at once
  }
  EXPECT_TRUE(answers_.empty());  // answered by the return value only
}

// A run the drive cannot take because it is tripped says so: the fault it reports, and what
// clears it. A refusal with no fault reported keeps to the result alone (the adapter's README
// says when its drive refuses).
TEST_F(AuditTest, ARunRefusedByATrippedDriveSaysWhichFault) {
  fake_->common_.faults.set(Fault::stall);
  fake_->common_.native_fault = 0x08;
  fake_->refuse_command = Command::run_forward;
  EXPECT_EQ(write(modbus_client(AccessLevel::operate), kCommand, {1}, 0ms), Outcome::refused);
  fake_->common_.faults = FaultSet{};
  fake_->common_.native_fault = 0;
  EXPECT_EQ(write(modbus_client(AccessLevel::operate), kCommand, {1}, 10ms), Outcome::refused);
  const auto c = commands();
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].field("result"), "refused");
  EXPECT_EQ(c[0].field("why"),
            "the drive reports a fault: stall (native 0x8); it runs again after reset_fault");
  EXPECT_THAT(c[0].message, ::testing::EndsWith(
                                "command=run_forward: " + std::string(to_string(Outcome::refused)) +
                                " (the drive reports a fault: stall (native "
                                "0x8); it runs again after reset_fault)"))
      << "the log line";
  EXPECT_EQ(c[1].field("why"), "");
}

TEST_F(AuditTest, TwoClientsAskingTheSameAreTwoRecords) {
  ASSERT_EQ(write(modbus_client(AccessLevel::maintain, "10.0.0.1:1"), kLimit, {0, 50}, 0ms),
            Outcome::ok);
  ASSERT_EQ(write(modbus_client(AccessLevel::maintain, "10.0.0.2:2"), kLimit, {0, 70}, 0ms),
            Outcome::ok);
  ASSERT_EQ(write(modbus_client(AccessLevel::maintain, "10.0.0.3:3"), kLimit, {0, 70}, 0ms),
            Outcome::ok);  // joins the one before it (coalesced)
  confirm(10ms);
  device_->next_exchange(at(10ms), Turn::write);
  confirm(20ms);
  const auto c = commands();
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0].field("client"), "10.0.0.1:1");
  EXPECT_EQ(c[1].field("client"), "10.0.0.2:2");
  EXPECT_EQ(c[2].field("client"), "10.0.0.3:3");
  EXPECT_EQ(c[2].field("points"), "limit=70");
  for (const Event& e : c) EXPECT_EQ(e.field("result"), "ok");
}

TEST_F(AuditTest, AnMqttCommandIsRecordedWithTheBrokerAndHost) {
  const MappedPoint* command = device_->map().at(Table::holding, kCommand);
  const Device::PointWrite w[] = {{command, std::int64_t{1}}};
  const Session mqtt{AccessLevel::operate, WordOrder::big, false,
                     Source{.kind = SourceKind::mqtt,
                            .listener = "mqtt://broker:1883",
                            .client = "drivegate-edge (primary host scada)"}};
  ASSERT_EQ(device_->write_points(mqtt, w, [this](Outcome o) { answers_.push_back(o); }, at(0ms)),
            Outcome::ok);
  device_->next_exchange(at(0ms), Turn::write);
  confirm(5ms);
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].field("source"), "mqtt");
  EXPECT_EQ(c[0].field("listener"), "mqtt://broker:1883");
  EXPECT_EQ(c[0].field("points"), "command=run_forward");
  EXPECT_EQ(c[0].field("result"), "ok");
}

TEST_F(AuditTest, TheFailsafeStopIsRecordedAsTheFailsafesWithItsTrip) {
  ASSERT_EQ(write(modbus_client(AccessLevel::operate), kCommand, {1}, 0ms), Outcome::ok);
  fake_->common_.command = Command::run_forward;
  fake_->common_.running = true;
  confirm(0ms);
  for (int ms = 100; ms <= 1000; ms += 100) {
    device_->link().health.frame_good(at(Millis(ms)));
    tick(Millis(ms));
  }
  device_->next_exchange(at(1000ms), Turn::write);
  fake_->common_.command = Command::stop;
  fake_->common_.running = false;
  confirm(1050ms);
  const auto c = commands();
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[1].field("source"), "failsafe");
  EXPECT_EQ(c[1].field("points"), "command=stop");
  EXPECT_EQ(c[1].field("result"), "ok");
  // Each write is recorded as it settles, then what the drive then reports.
  EXPECT_THAT(kinds(), ElementsAre(EventKind::command, EventKind::drive_started,
                                   EventKind::failsafe_tripped, EventKind::command,
                                   EventKind::drive_stopped));
  const auto trip = history_.events().query({.kind = EventKind::failsafe_tripped});
  ASSERT_EQ(trip.size(), 1u);
  EXPECT_EQ(trip[0].field("action"), "stop");
  // A run from the PLC clears it.
  ASSERT_EQ(write(modbus_client(AccessLevel::operate), kCommand, {1}, 1100ms), Outcome::ok);
  EXPECT_EQ(history_.events().query({.kind = EventKind::failsafe_cleared}).size(), 1u);
}

TEST_F(AuditTest, TheShutdownStopIsRecordedAsShutdowns) {
  fake_->common_.running = true;
  device_->command(Command::stop, [this](Outcome o) { answers_.push_back(o); }, at(0ms),
                   SourceKind::shutdown);
  confirm(30ms);
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].field("source"), "shutdown");
  EXPECT_EQ(c[0].field("points"), "command=stop");
  EXPECT_EQ(c[0].field("took_ms"), "30");
}

TEST_F(AuditTest, AWriteTheDriveNeverAnsweredIsRecordedAsSuch) {
  ASSERT_EQ(write(modbus_client(AccessLevel::operate), kCommand, {1}, 0ms), Outcome::ok);
  tick(2500ms);  // no frame since t0: comm lost, the write with it
  ASSERT_THAT(answers_, ElementsAre(Outcome::no_response));
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].field("result"), "no_response");
  EXPECT_EQ(c[0].field("why"), "comm lost");
  EXPECT_EQ(c[0].field("took_ms"), "2500");
  EXPECT_EQ(history_.events().query({.kind = EventKind::comm_lost}).size(), 1u);
  device_->link().health.frame_good(at(2600ms));
  device_->on_receive({}, at(2600ms));
  EXPECT_EQ(history_.events().query({.kind = EventKind::comm_restored}).size(), 1u);
}

TEST_F(AuditTest, TheHeartbeatAloneIsCountedNotRecorded) {
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(write(modbus_client(AccessLevel::operate), kHeartbeat,
                    {static_cast<std::uint16_t>(i)}, Millis(i * 100)),
              Outcome::ok);
  }
  EXPECT_TRUE(commands().empty());
  EXPECT_EQ(history_.audit().counts().at(SourceKind::modbus, Outcome::ok), 20u);
}

TEST_F(AuditTest, FaultsRaisedAndClearedAreEventsWithTheNativeCode) {
  fake_->common_.faults.set(Fault::over_current);
  fake_->common_.native_fault = 0x21;
  device_->on_receive({}, at(10ms));
  fake_->common_.faults = FaultSet{};
  fake_->common_.native_fault = 0;
  device_->on_receive({}, at(20ms));
  const auto all = history_.events().query({});
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].kind, EventKind::fault_raised);
  EXPECT_EQ(all[0].field("fault"), "over_current");
  EXPECT_EQ(all[0].field("native"), "0x21");
  EXPECT_EQ(all[1].kind, EventKind::fault_cleared);
}

// A PLC writing command, setpoint and a counting heartbeat every scan: the same command each
// time, one entry counting its repeats (the heartbeat is the gateway's, not part of the record).
TEST_F(AuditTest, ACommandWordWrittenEveryScanWithItsHeartbeatIsOneEntry) {
  for (int scan = 0; scan < 20; ++scan) {
    ASSERT_EQ(write(modbus_client(AccessLevel::operate), kCommand,
                    {1, 800, static_cast<std::uint16_t>(scan)}, Millis(100 * scan)),
              Outcome::ok);
    confirm(Millis(100 * scan + 5));
  }
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].field("points"), "setpoint_rpm=800 command=run_forward");
  EXPECT_EQ(c[0].field("repeats"), "19");
  EXPECT_EQ(journal_.entries.size(), 1u);
}

// A drive that stopped answering has not stopped running nor cleared its faults as far as anyone
// knows: nothing of its own is recorded until it answers again. The first state heard is "found".
TEST_F(AuditTest, NothingTheDriveSaysCountsWhileItDoesNotAnswer) {
  fake_->common_.running = true;
  fake_->common_.command = Command::run_forward;
  device_->on_receive({}, at(10ms));
  auto started = history_.events().query({.kind = EventKind::drive_started});
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ(started[0].field("found"), "true");
  EXPECT_EQ(started[0].message, "dev: found running (run_forward, setpoint 0 rpm)");
  tick(2500ms);  // comm lost; the driver's stale state says stopped and faulted meanwhile
  fake_->common_.running = false;
  fake_->common_.faults.set(Fault::over_current);
  device_->on_no_reply(at(2600ms));
  EXPECT_TRUE(history_.events().query({.kind = EventKind::drive_stopped}).empty());
  EXPECT_TRUE(history_.events().query({.kind = EventKind::fault_raised}).empty());
  // Answering again: now what it says is news.
  device_->link().health.frame_good(at(2700ms));
  device_->on_receive({}, at(2700ms));
  EXPECT_THAT(kinds(), ElementsAre(EventKind::drive_started, EventKind::comm_lost,
                                   EventKind::comm_restored, EventKind::fault_raised,
                                   EventKind::drive_stopped));
  EXPECT_EQ(history_.events().query({.kind = EventKind::fault_raised})[0].field("found"),
            "false");
}

}  // namespace
}  // namespace drivegate
