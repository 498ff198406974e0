// Reload: a device whose settings are unchanged moves to the new gateway as it runs, whatever
// changes beside it; a bus whose own settings are unchanged keeps its port open. A device whose
// settings changed starts afresh, but the PLC's watchdog goes with it (docs/safety.md, "A reload
// and the failsafe"): armed with its deadline, or latched. The devices are driven here through
// their Station calls on a time the test sets, as the engine and the failsafe tests drive them.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <boost/asio/io_context.hpp>

#include "plugin/adapter_options.h"
#include "fake_adapter.h"
#include "gateway/gateway.h"

namespace drivegate {
namespace {

using namespace std::chrono_literals;

class GatewayReload : public ::testing::Test {
 protected:
  GatewayReload() { plugins_.add(test::kFakeAdapter); }

  // Two lines: "a" with devices a1 (unit 1) and a2 (unit 2), "b" with b1 (unit 3). The ports do
  // not exist; nothing here is started.
  static Config config() {
    Config c;
    c.path = "drivegate.toml";
    for (const char* name : {"a", "b"}) {
      BusConfig b;
      b.name = name;
      b.port = std::string("/nonexistent/tty-") + name;
      b.baud = 4800;
      c.buses.push_back(b);
    }
    const auto device = [](const char* name, const char* bus, std::uint8_t unit) {
      DeviceConfig d;
      d.name = name;
      d.bus = bus;
      d.adapter = "fake";
      d.unit_id = unit;
      d.address = unit;
      d.options = default_options(test::kFakeAdapter);
      return d;
    };
    c.devices = {device("a1", "a", 1), device("a2", "a", 2), device("b1", "b", 3)};
    return c;
  }

  std::unique_ptr<Gateway> build(const Config& c) {
    std::vector<std::string> errors;
    auto gw = Gateway::build(io_, c, plugins_, log_, errors, false, &history_);
    EXPECT_TRUE(errors.empty()) << errors.front();
    return gw;
  }

  // The fake driver behind a device the gateway built (the test scripts it as the drive).
  static test::FakeDriver& fake(Device& d) {
    return const_cast<test::FakeDriver&>(dynamic_cast<const test::FakeDriver&>(d.driver()));
  }
  TimePoint at(Millis ms) const { return t0_ + ms; }
  // The drive answers, ready, and the device's housekeeping tick runs, as the engine runs it.
  void tick(Device& d, Millis ms) {
    fake(d).common_.ready = true;
    d.link().health.data_good(at(ms), at(ms));
    d.on_tick(at(ms));
  }
  // The PLC runs the drive at `rpm` and the drive confirms it at once.
  void plc_runs(Device& d, Millis ms, std::uint16_t rpm = 800) {
    const std::vector<std::uint16_t> run = {1 /*run_forward*/, rpm};
    ASSERT_EQ(d.write(
                  kPlc, Table::holding, 0, run, [](Outcome) {}, at(ms)),
              Outcome::ok);
    d.next_exchange(at(ms), Turn::write);
    fake(d).completions.push_back({fake(d).last_ticket, WriteResult::ok});
    fake(d).common_.command = Command::run_forward;
    fake(d).common_.running = true;
    d.next_exchange(at(ms), Turn::poll);
  }
  Outcome heartbeat(Device& d, Millis ms) {
    const std::uint16_t beat = 7;
    return d.write(
        kPlc, Table::holding, 2, std::span(&beat, 1), [](Outcome) {}, at(ms));
  }
  // `a1` with the failsafe on (stop after `timeout`).
  static Config with_failsafe(Millis timeout = 2000ms) {
    auto c = config();
    c.devices[0].failsafe.timeout = timeout;
    c.devices[0].failsafe.action = FailsafeAction::stop;
    return c;
  }
  // The history's entries about `device` of `kind`, oldest first.
  std::vector<Event> events(const std::string& device, EventKind kind) {
    EventFilter f;
    f.device = device;
    f.kind = kind;
    return history_.events().query(f);
  }

  static inline const Session kPlc{AccessLevel::operate, WordOrder::big};
  TimePoint t0_ = TimePoint{} + std::chrono::hours(1);
  History history_;

  boost::asio::io_context io_;
  PluginRegistry plugins_;
  std::shared_ptr<spdlog::logger> log_ =
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());
};

TEST_F(GatewayReload, AnUnchangedConfigKeepsEveryBusAndDevice) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  const Device* b1 = old->find("b1");
  const Bus* bus_a = old->buses()[0].get();
  auto next = build(config());
  next->adopt(*old);
  EXPECT_EQ(next->find("a1"), a1);  // the same objects, with their state
  EXPECT_EQ(next->find("b1"), b1);
  EXPECT_EQ(next->buses()[0].get(), bus_a);  // the same line, port open
  EXPECT_TRUE(old->devices().empty());
  EXPECT_TRUE(old->buses().empty());
  EXPECT_EQ(next->devices().size(), 3u);
}

TEST_F(GatewayReload, WhereItWasDeclaredDoesNotCount) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  auto moved = config();
  for (auto& b : moved.buses) b.line += 40;
  for (auto& d : moved.devices) d.line += 40;
  auto next = build(moved);
  next->adopt(*old);
  EXPECT_EQ(next->find("a1"), a1);
  EXPECT_TRUE(old->buses().empty());
}

// A neighbour's change on the line leaves a device as it runs, and the line open.
TEST_F(GatewayReload, AChangedDeviceStartsAfreshAloneItsNeighboursAndLineKept) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  const Device* a2 = old->find("a2");
  const Bus* bus_a = old->buses()[0].get();
  auto changed = config();
  changed.devices[1].poll_interval = Millis(250);  // a2, on bus a
  auto next = build(changed);
  next->adopt(*old);
  EXPECT_EQ(next->find("a1"), a1);  // kept, on the kept line
  EXPECT_NE(next->find("a2"), a2);  // afresh
  EXPECT_EQ(next->buses()[0].get(), bus_a);
  EXPECT_EQ(old->devices().size(), 1u);  // the old a2 stays behind, to be stopped
  // The kept line now polls the kept a1 and the new a2, not the old a2.
  const auto& stations = bus_a->stations();
  ASSERT_EQ(stations.size(), 2u);
  EXPECT_EQ(stations[0], static_cast<const Station*>(a1));
  EXPECT_EQ(stations[1], static_cast<const Station*>(next->find("a2")));
}

TEST_F(GatewayReload, ChangedLineSettingsReopenTheLineButKeepItsDevices) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  const Bus* bus_a = old->buses()[0].get();
  auto changed = config();
  changed.buses[0].baud = 9600;
  auto next = build(changed);
  next->adopt(*old);
  EXPECT_NE(next->buses()[0].get(), bus_a);  // a new line (the old one is stopped first)
  EXPECT_EQ(next->find("a1"), a1);           // the device, as it ran
  EXPECT_EQ(next->buses()[0]->stations().front(), static_cast<const Station*>(a1));
  EXPECT_EQ(old->buses().size(), 1u);
}

TEST_F(GatewayReload, AnAddedDeviceJoinsAKeptLine) {
  auto old = build(config());
  const Device* b1 = old->find("b1");
  const Bus* bus_b = old->buses()[1].get();
  auto added = config();
  added.devices.push_back(added.devices[2]);
  added.devices.back().name = "b2";
  added.devices.back().unit_id = 4;
  added.devices.back().address = 4;
  auto next = build(added);
  next->adopt(*old);
  EXPECT_EQ(next->find("b1"), b1);
  EXPECT_EQ(next->buses()[1].get(), bus_b);
  EXPECT_EQ(bus_b->stations().size(), 2u);
}

TEST_F(GatewayReload, ReadsReachTheKeptDevicesByUnit) {
  auto old = build(config());
  auto next = build(config());
  next->adopt(*old);
  old.reset();  // the old gateway is gone; the kept devices live on in the new one
  std::array<std::uint16_t, 1> status{};
  for (const std::uint8_t unit : {std::uint8_t{1}, std::uint8_t{2}, std::uint8_t{3}}) {
    EXPECT_EQ(next->read({}, unit, Table::input, 0, status), Outcome::ok);
  }
  EXPECT_EQ(next->read({}, 4, Table::input, 0, status), Outcome::no_such_device);
}

// The reload: the PLC runs a drive with a 2 s failsafe and goes away; half a second later
// a reload changes the device's own settings (its adapter, here its poll_ms and unit id). The new
// device trips at the deadline the PLC's last write set, not later and not never, and stops the
// drive it now drives.
TEST_F(GatewayReload, AChangedDeviceKeepsTheArmedFailsafeAndItsDeadline) {
  auto old = build(with_failsafe());
  Device& before = *old->find("a1");
  tick(before, 0ms);
  ASSERT_NO_FATAL_FAILURE(plc_runs(before, 0ms));
  tick(before, 500ms);
  auto changed = with_failsafe();
  changed.devices[0].poll_interval = 250ms;
  changed.devices[0].unit_id = 9;  // keyed by name, not by unit id
  auto next = build(changed);
  next->adopt(*old);
  Device& after = *next->find("a1");
  ASSERT_NE(&after, &before);                          // afresh
  fake(after).common_.command = Command::run_forward;  // found running
  fake(after).common_.running = true;
  for (int ms = 600; ms < 2000; ms += 100) tick(after, Millis(ms));
  EXPECT_TRUE(fake(after).commands.empty()) << "tripped before the deadline";
  EXPECT_FALSE(after.failsafe_latched());
  tick(after, 2000ms);
  EXPECT_EQ(fake(after).commands, std::vector<Command>{Command::stop});
  EXPECT_TRUE(after.failsafe_latched());
  std::uint16_t status = 0;
  ASSERT_EQ(next->read(kPlc, 9, Table::input, 0, std::span(&status, 1)), Outcome::ok);
  EXPECT_NE(status & (1u << 5), 0u);  // StatusBit::failsafe, where the PLC reads it now
}

// A latched failsafe stays latched across the change: the status bit stays set, the new device
// sends its stop to the drive it finds running, a run from a source that does not feed the
// failsafe is refused, and the history does not say it tripped twice.
TEST_F(GatewayReload, ALatchedFailsafeStaysLatchedAcrossAChange) {
  auto old = build(with_failsafe());
  Device& before = *old->find("a1");
  tick(before, 0ms);
  ASSERT_NO_FATAL_FAILURE(plc_runs(before, 0ms));
  tick(before, 2000ms);
  ASSERT_TRUE(before.failsafe_latched());
  auto changed = with_failsafe();
  changed.devices[0].budget = 900ms;
  auto next = build(changed);
  next->adopt(*old);
  Device& after = *next->find("a1");
  ASSERT_NE(&after, &before);
  EXPECT_TRUE(after.failsafe_latched());
  fake(after).common_.command = Command::run_forward;  // the old stop never reached it
  fake(after).common_.running = true;
  tick(after, 2100ms);
  EXPECT_EQ(fake(after).commands, std::vector<Command>{Command::stop});
  Session mqtt{AccessLevel::operate, WordOrder::big, false};
  const std::uint16_t run = 1;
  EXPECT_EQ(after.write(
                mqtt, Table::holding, 0, std::span(&run, 1), [](Outcome) {}, at(2200ms)),
            Outcome::refused);
  EXPECT_EQ(events("a1", EventKind::failsafe_tripped).size(), 1u);
}

// The rule for a reload that changes the failsafe itself (docs/safety.md): the deadline running
// stands, the new timeout counts from the PLC's next write. A longer timeout does not put off a
// deadline already set...
TEST_F(GatewayReload, ANewTimeoutCountsFromThePlcsNextWrite) {
  auto old = build(with_failsafe(2000ms));
  Device& before = *old->find("a1");
  tick(before, 0ms);
  ASSERT_NO_FATAL_FAILURE(plc_runs(before, 0ms));
  auto next = build(with_failsafe(5000ms));
  next->adopt(*old);
  Device& after = *next->find("a1");
  fake(after).common_.command = Command::run_forward;
  fake(after).common_.running = true;
  tick(after, 1900ms);
  EXPECT_FALSE(after.failsafe_latched());
  tick(after, 2000ms);
  EXPECT_TRUE(after.failsafe_latched());  // the old deadline
  // ...and once the PLC is back, its run clears the latch and the new timeout counts from it.
  ASSERT_NO_FATAL_FAILURE(plc_runs(after, 3000ms));
  EXPECT_FALSE(after.failsafe_latched());
  tick(after, 7900ms);
  EXPECT_FALSE(after.failsafe_latched());
  tick(after, 8000ms);
  EXPECT_TRUE(after.failsafe_latched());
}

// ...nor does turning the failsafe off cancel it: the deadline the PLC's last write set still
// stops the drive. From the PLC's next write on it is off.
TEST_F(GatewayReload, TurningTheFailsafeOffTakesEffectAtThePlcsNextWrite) {
  auto old = build(with_failsafe(2000ms));
  Device& before = *old->find("a1");
  tick(before, 0ms);
  ASSERT_NO_FATAL_FAILURE(plc_runs(before, 0ms));
  auto next = build(with_failsafe(0ms));
  next->adopt(*old);
  Device& after = *next->find("a1");
  fake(after).common_.command = Command::run_forward;
  fake(after).common_.running = true;
  tick(after, 2000ms);
  EXPECT_TRUE(after.failsafe_latched());
  EXPECT_EQ(fake(after).commands, std::vector<Command>{Command::stop});
  ASSERT_NO_FATAL_FAILURE(plc_runs(after, 3000ms));  // clears the latch
  EXPECT_FALSE(after.failsafe_latched());
  for (int ms = 3100; ms <= 20'000; ms += 100) tick(after, Millis(ms));
  EXPECT_FALSE(after.failsafe_latched());  // off from that write on
}

// A watchdog never armed (no PLC wrote) is not armed by a reload, and one the new configuration
// turns on starts at the PLC's next write, as at start-up.
TEST_F(GatewayReload, AFailsafeTurnedOnStartsAtTheNextWrite) {
  auto old = build(config());
  Device& before = *old->find("a1");
  tick(before, 0ms);
  ASSERT_NO_FATAL_FAILURE(plc_runs(before, 0ms));
  auto next = build(with_failsafe(2000ms));
  next->adopt(*old);
  Device& after = *next->find("a1");
  for (int ms = 100; ms <= 5000; ms += 100) tick(after, Millis(ms));
  EXPECT_FALSE(after.failsafe_latched());
  ASSERT_EQ(heartbeat(after, 5000ms), Outcome::ok);
  tick(after, 6900ms);
  EXPECT_FALSE(after.failsafe_latched());
  tick(after, 7000ms);
  EXPECT_TRUE(after.failsafe_latched());
}

// The history says what the new device found the drive doing once the driver knows (ready), as
// the log does: not "running (stop)" from a half-read state, and as found, not as a change.
TEST_F(GatewayReload, TheHistorySaysWhatAChangedDeviceFoundOnceItKnows) {
  auto old = build(config());
  auto changed = config();
  changed.devices[0].poll_interval = 250ms;
  auto next = build(changed);
  next->adopt(*old);
  Device& d = *next->find("a1");
  test::FakeDriver& drive = fake(d);
  // The first blocks read: speed, not yet the status word.
  drive.common_.ready = false;
  d.link().health.data_good(at(0ms), at(0ms));
  d.on_tick(at(0ms));
  // The status word: running, while the command in force is not known yet.
  drive.common_.running = true;
  drive.common_.speed_rpm = 1500;
  d.on_tick(at(100ms));
  // Every block read: the driver adopts the run it found.
  drive.common_.ready = true;
  drive.common_.command = Command::run_forward;
  drive.common_.setpoint_rpm = 1500;
  d.link().health.data_good(at(200ms), at(200ms));
  d.on_tick(at(200ms));
  const auto started = events("a1", EventKind::drive_started);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ(started[0].field("found"), "true");
  EXPECT_EQ(started[0].field("command"), "run_forward");
  EXPECT_EQ(started[0].field("setpoint_rpm"), "1500");
}

// A write on its way to the drive when a reload replaces its device gets what the drive says of
// it, and the audit with it: the reload holds the old device until the write settles (a client's
// other writes refused busy meanwhile, a stop carried out, a kept neighbour untouched), and only
// then puts the new one in its place. Without the hold the write failed "the gateway stopped"
// (0x0B to the PLC) while the drive had taken it.
TEST_F(GatewayReload, AWriteInFlightSettlesWithTheDrivesAnswerBeforeItsDeviceGoes) {
  auto old = build(config());
  Device& before = *old->find("a1");
  Device& neighbour = *old->find("a2");
  tick(before, 0ms);
  tick(neighbour, 0ms);
  std::vector<Outcome> answers;
  const auto keep = [&](Outcome o) { answers.push_back(o); };
  const std::vector<std::uint16_t> run = {1 /*run_forward*/, 800};
  ASSERT_EQ(before.write(kPlc, Table::holding, 0, run, keep, at(0ms)), Outcome::ok);
  before.next_exchange(at(0ms), Turn::write);  // on the line: the drive's answer is to come
  const Ticket run_ticket = fake(before).last_ticket;
  ASSERT_EQ(fake(before).commands, std::vector<Command>{Command::run_forward});

  auto changed = config();
  changed.devices[0].poll_interval = 250ms;  // a1 changes, a2 and b1 are kept
  auto next = build(changed);
  EXPECT_EQ(old->hold_for_reload(*next), before.write_timeout());
  EXPECT_EQ(old->held_writes(), 1u);
  const std::uint16_t faster = 900;
  EXPECT_EQ(before.write(kPlc, Table::holding, 1, std::span(&faster, 1), keep, at(20ms)),
            Outcome::busy);
  EXPECT_TRUE(fake(before).setpoints == std::vector<std::int32_t>{800});  // never reached it
  EXPECT_EQ(heartbeat(before, 20ms), Outcome::ok);
  std::vector<Outcome> neighbours;
  ASSERT_EQ(neighbour.write(
                kPlc, Table::holding, 1, std::span(&faster, 1),
                [&](Outcome o) { neighbours.push_back(o); }, at(20ms)),
            Outcome::ok);  // kept: not held
  EXPECT_EQ(neighbours, std::vector<Outcome>{Outcome::ok});
  EXPECT_EQ(fake(neighbour).setpoints, std::vector<std::int32_t>{900});
  EXPECT_EQ(old->held_writes(), 1u);
  const std::uint16_t stop = 0;
  ASSERT_EQ(before.write(kPlc, Table::holding, 0, std::span(&stop, 1), keep, at(30ms)),
            Outcome::ok);
  const Ticket stop_ticket = fake(before).last_ticket;
  EXPECT_EQ(fake(before).commands, (std::vector<Command>{Command::run_forward, Command::stop}));
  EXPECT_EQ(old->held_writes(), 2u);

  fake(before).completions.push_back({run_ticket, WriteResult::ok});
  fake(before).completions.push_back({stop_ticket, WriteResult::ok});
  before.next_exchange(at(60ms), Turn::poll);
  EXPECT_EQ(answers, (std::vector<Outcome>{Outcome::ok, Outcome::ok}));
  EXPECT_EQ(old->held_writes(), 0u);

  next->adopt(*old);
  old->stop();
  EXPECT_EQ(answers.size(), 2u);  // nothing failed by the stop
  std::vector<std::string> audit;
  for (const Event& e : events("a1", EventKind::command)) {
    audit.push_back(std::string(e.field("points")) + " " + std::string(e.field("result")) + " " +
                    std::string(e.field("why")));
  }
  EXPECT_EQ(audit, (std::vector<std::string>{
                       "setpoint_rpm=900 busy a reload is replacing the device: try again",
                       "setpoint_rpm=800 command=run_forward ok ", "command=stop ok "}));
  EXPECT_EQ(next->find("a2"), &neighbour);
}

}  // namespace
}  // namespace drivegate
