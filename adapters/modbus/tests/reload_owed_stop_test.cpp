// A reload (or a shutdown) while a stop is owed to a fan its set value runs (docs/profiles.md, "A
// set value that runs the drive"): the fan tripped while running, the driver's own stop (set value
// 0) did not reach it, and the device is changed by a reload, or the daemon stops, before it did.
// The new driver owes the same stop (Driver::owed, Device::take_over), so that a fan whose fault
// cleared meanwhile, turning again at its old set value, is stopped rather than adopted as running.
// The real modbus driver in devices the gateway builds and replaces, driven through their Station
// calls on a time the test sets, the slave played by hand (support::ReloadRig).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common_block.h"
#include "reload_support.h"

namespace drivegate::modbus_device::modbus_reload_owed_stop_test {
namespace {

using namespace std::chrono_literals;

constexpr std::uint8_t kSlave = 9;

constexpr std::uint16_t kErrorBit = 1u << 4;

// The fan as the test plays it: its registers, and whether it answers writes.
struct FanState {
  std::uint16_t set_value = 0;
  std::uint16_t speed = 0;
  std::uint16_t status = 0;
  bool answers_writes = true;
};

class ReloadOwedStop : public support::ReloadRig {
 protected:
  ReloadOwedStop() : ReloadRig(support::kFanProfile, "fan.toml") {}

  [[nodiscard]] Config config(Millis poll, std::uint32_t address = kSlave) const {
    DeviceConfig d = device("fan", address);
    d.poll_interval = poll;
    return ReloadRig::config(d);
  }

  // One exchange of `d` on a write turn, or a poll turn when it has no write: each frame kept in
  // sent_, reads answered from fan_, FC 06 writes put in force and echoed (or unanswered).
  void exchange(Device& d, Millis ms) {
    auto ex = d.next_exchange(at(ms), Turn::write);
    if (!ex) ex = d.next_exchange(at(ms), Turn::poll);
    if (!ex) {
      d.on_tick(at(ms));
      return;
    }
    const Bytes& f = ex->frame;
    sent_.push_back(f);
    const std::uint8_t address = f[0];
    const std::uint16_t start = static_cast<std::uint16_t>(f[2] << 8 | f[3]);
    const std::uint16_t value = static_cast<std::uint16_t>(f[4] << 8 | f[5]);
    if (f[1] == 0x06) {
      if (!fan_.answers_writes) {
        d.on_no_reply(at(ms));
        d.on_tick(at(ms));
        return;
      }
      if (start == 1) fan_.set_value = value;
      d.on_receive(f, at(ms));
    } else {
      std::vector<std::uint16_t> words(value, 0);
      for (std::uint16_t i = 0; i < value; ++i) {
        const auto a = static_cast<std::uint16_t>(start + i);
        if (f[1] == 0x03 && a == 1) words[i] = fan_.set_value;
        if (f[1] == 0x04 && a == 16) words[i] = fan_.speed;
        if (f[1] == 0x04 && a == 17) words[i] = fan_.status;
      }
      d.link().health.frame_good(at(ms));
      d.on_receive(encode(Framing::rtu, address, support::words_pdu(f[1], words)), at(ms));
      d.link().health.data_good(at(ms), at(ms));
    }
    d.on_tick(at(ms));
  }
  // Exchanges every `step` from `from` for `count` turns.
  void run(Device& d, Millis from, int count, Millis step = 10ms) {
    for (int i = 0; i < count; ++i) exchange(d, from + i * step);
  }
  // The FC 06 writes of the set value sent from `from` on.
  std::vector<std::uint16_t> set_values_from(std::size_t from) const {
    std::vector<std::uint16_t> out;
    for (std::size_t i = from; i < sent_.size(); ++i) {
      const Bytes& f = sent_[i];
      if (f[1] == 0x06 && f[2] == 0 && f[3] == 1)
        out.push_back(static_cast<std::uint16_t>(f[4] << 8 | f[5]));
    }
    return out;
  }

  // The old gateway's fan: found running at 1000 rpm (adopted), then tripped, its stop written
  // and never answered: owed. Returns that gateway.
  std::unique_ptr<Gateway> tripped_with_a_stop_owed() {
    auto old = build(config(500ms));
    Device& d = *old->find("fan");
    fan_ = {1000, 1000, 0, true};
    run(d, 0ms, 10);
    EXPECT_TRUE(d.online());
    EXPECT_EQ(d.state().command, Command::run_forward);  // adopted: its set value runs it
    fan_.status = kErrorBit;
    fan_.speed = 0;
    fan_.answers_writes = false;
    const std::size_t mark = sent_.size();
    run(d, 600ms, 20);
    EXPECT_EQ(d.state().command, Command::stop);
    EXPECT_THAT(set_values_from(mark), ::testing::Contains(0));  // its stop, not answered
    EXPECT_EQ(fan_.set_value, 1000);
    EXPECT_TRUE(d.driver().owed().stop_after_trip);
    return old;
  }

  // The old gateway's fan: adopted running at 1000 rpm, tripped (the driver's stop written and
  // taken), then run again by the PLC with the trip shown: that run is in force, not ended by the
  // trip, the fan still (tripped) at set value 1000, and no stop owed.
  std::unique_ptr<Gateway> run_with_its_trip_shown() {
    auto gw = build(config(500ms));
    Device& d = *gw->find("fan");
    fan_ = {1000, 1000, 0, true};
    run(d, 0ms, 10);
    fan_.status = kErrorBit;
    fan_.speed = 0;
    run(d, 600ms, 20);
    EXPECT_EQ(fan_.set_value, 0);  // the trip's stop
    // The PLC reads the trip, then asks for the run.
    EXPECT_NE(plc_reads_status(d, at(1000ms)) & test::common_block::kFaulted, 0u);
    const std::uint16_t go = 1;  // run_forward
    EXPECT_EQ(d.write(
                  kPlc, Table::holding, 0, std::span(&go, 1), [](Outcome) {}, at(1000ms)),
              Outcome::ok);
    run(d, 1000ms, 80);  // past two more polls showing the trip
    EXPECT_EQ(fan_.set_value, 1000);
    EXPECT_EQ(d.state().command, Command::run_forward);
    EXPECT_FALSE(d.state().running);
    EXPECT_FALSE(d.driver().owed().stop_after_trip);
    return gw;
  }

  // A gateway whose fan is online and still, with a setpoint `rpm` the PLC wrote: answered ok,
  // held by the driver, never written to the fan (its set value reads 0).
  std::unique_ptr<Gateway> still_with_a_setpoint_held(std::uint16_t rpm) {
    auto gw = build(config(500ms));
    Device& d = *gw->find("fan");
    fan_ = {0, 0, 0, true};
    run(d, 0ms, 10);
    EXPECT_TRUE(d.online());
    std::vector<Outcome> answers;
    EXPECT_EQ(d.write(
                  kPlc, Table::holding, 1, std::span(&rpm, 1),
                  [&](Outcome o) { answers.push_back(o); }, at(200ms)),
              Outcome::ok);
    run(d, 200ms, 5);
    EXPECT_THAT(answers, ::testing::ElementsAre(Outcome::ok));
    EXPECT_EQ(d.state().setpoint_rpm, rpm);
    EXPECT_EQ(fan_.set_value, 0);
    return gw;
  }

  FanState fan_;
};

// The fault clears during the reload and the fan turns again at its old set value: the new driver
// writes the stop owed, and the PLC reads stop, never a run nobody asked for.
TEST_F(ReloadOwedStop, TheNewDriverWritesTheStopTheOldOneOwed) {
  auto old = tripped_with_a_stop_owed();
  auto next = build(config(250ms));  // the poll interval changed: a changed device
  Device& fresh = reload(*old, *next, "fan");
  fan_.status = 0;  // the fault cleared by itself: the fan turns at its old set value
  fan_.speed = 1000;
  fan_.answers_writes = true;
  const std::size_t mark = sent_.size();
  run(fresh, 2000ms, 20);
  ASSERT_TRUE(fresh.online());
  EXPECT_EQ(set_values_from(mark), std::vector<std::uint16_t>{0});
  EXPECT_EQ(fan_.set_value, 0);
  EXPECT_EQ(fresh.state().command, Command::stop);
  EXPECT_FALSE(fresh.driver().owed().stop_after_trip);  // paid: the drive confirmed it
}

// Moved to another address, it is another fan: nothing is owed to it, and one found turning is
// adopted as running, as at any start.
TEST_F(ReloadOwedStop, AnotherDriveIsOwedNothing) {
  auto old = tripped_with_a_stop_owed();
  auto next = build(config(500ms, kSlave + 1));
  Device& fresh = reload(*old, *next, "fan");
  fan_ = {1000, 1000, 0, true};
  const std::size_t mark = sent_.size();
  run(fresh, 2000ms, 20);
  ASSERT_TRUE(fresh.online());
  EXPECT_THAT(set_values_from(mark), ::testing::IsEmpty());
  EXPECT_EQ(fresh.state().command, Command::run_forward);
}

// A setpoint a PLC wrote while the fan stood still is held by the driver and never written to the
// fan (its set value reads 0). A reload that changes the device hands it to the new driver, so the
// PLC reads it still and its next bare run runs at it, rather than being refused with nothing to
// run at.
TEST_F(ReloadOwedStop, TheSetpointHeldForTheNextRunIsCarriedOver) {
  auto old = still_with_a_setpoint_held(800);
  auto next = build(config(250ms));
  Device& fresh = reload(*old, *next, "fan");
  run(fresh, 1000ms, 20);
  ASSERT_TRUE(fresh.online());
  EXPECT_EQ(fresh.state().setpoint_rpm, 800);
  EXPECT_EQ(fresh.state().command, Command::stop);
  const std::size_t mark = sent_.size();
  std::vector<Outcome> answers;
  const std::uint16_t go = 1;  // run_forward
  ASSERT_EQ(fresh.write(
                kPlc, Table::holding, 0, std::span(&go, 1),
                [&](Outcome o) { answers.push_back(o); }, at(2000ms)),
            Outcome::ok);
  run(fresh, 2000ms, 5);
  EXPECT_THAT(answers, ::testing::ElementsAre(Outcome::ok));
  EXPECT_EQ(set_values_from(mark), std::vector<std::uint16_t>{800});
  EXPECT_EQ(fresh.state().command, Command::run_forward);
}

// The fan found turning by the new driver (another master ran it meanwhile): its set value is the
// setpoint in force, whatever the old driver held.
TEST_F(ReloadOwedStop, ASetValueReadNotZeroOutranksTheSetpointCarried) {
  auto old = still_with_a_setpoint_held(800);
  auto next = build(config(250ms));
  Device& fresh = reload(*old, *next, "fan");
  fan_ = {1200, 1200, 0, true};
  run(fresh, 1000ms, 20);
  ASSERT_TRUE(fresh.online());
  EXPECT_EQ(fresh.state().setpoint_rpm, 1200);
  EXPECT_EQ(fresh.state().command, Command::run_forward);  // adopted, as at any start
}

// A new profile that cannot write the setpoint held (its set value's range now ends below it):
// nothing is carried. The PLC reads 0, and its bare run is refused with nothing to run at, as at
// any start, rather than taken at a setpoint the profile cannot write.
TEST_F(ReloadOwedStop, ASetpointTheNewProfileCannotWriteIsNotCarried) {
  auto old = still_with_a_setpoint_held(2500);
  const support::ProfileFile narrow{
      support::replaced(support::kFanProfile, "max = 3000\n", "max = 2000\n"), "narrow.toml"};
  DeviceConfig changed = device("fan", kSlave);
  changed.options.set("profile", narrow.path);
  auto next = build(ReloadRig::config(changed));
  Device& fresh = reload(*old, *next, "fan");
  run(fresh, 1000ms, 20);
  ASSERT_TRUE(fresh.online());
  EXPECT_EQ(fresh.state().setpoint_rpm, 0);
  const std::size_t mark = sent_.size();
  std::vector<Outcome> answers;
  const std::uint16_t go = 1;  // run_forward
  const Outcome accepted = fresh.write(
      kPlc, Table::holding, 0, std::span(&go, 1), [&](Outcome o) { answers.push_back(o); },
      at(2000ms));
  run(fresh, 2000ms, 5);
  EXPECT_TRUE(accepted != Outcome::ok || (!answers.empty() && answers.front() != Outcome::ok));
  EXPECT_THAT(set_values_from(mark), ::testing::IsEmpty());
  EXPECT_EQ(fresh.state().command, Command::stop);
}

// The daemon shutting down while the stop is owed: the fan reads stopped (tripped), but its set
// value would restart it once the fault clears with no gateway left to stop it. Shutdown stops it,
// and waits for its answer before the daemon goes on to exit.
TEST_F(ReloadOwedStop, ShutdownWritesTheStopOwed) {
  auto gw = tripped_with_a_stop_owed();
  Device& d = *gw->find("fan");
  fan_.answers_writes = true;
  bool done = false;
  gw->stop_drives(2000ms, at(3000ms), [&] { done = true; });
  EXPECT_FALSE(done) << "shutdown went on without the stop owed";
  const std::size_t mark = sent_.size();
  run(d, 3000ms, 10);
  EXPECT_EQ(set_values_from(mark), std::vector<std::uint16_t>{0});
  EXPECT_EQ(fan_.set_value, 0);
  EXPECT_TRUE(done);
  EXPECT_FALSE(d.driver().owed().stop_after_trip);
}

// The daemon shutting down with a fan a PLC ran while its trip was shown: it reads stopped (no run
// bit, speed 0) and owes no stop, but its set value turns it once the fault clears, the gateway
// gone. Its command in force is a run: shutdown stops it, and waits for its answer.
TEST_F(ReloadOwedStop, ShutdownStopsAFanRunWithItsTripShown) {
  auto gw = run_with_its_trip_shown();
  Device& d = *gw->find("fan");
  bool done = false;
  gw->stop_drives(2000ms, at(3000ms), [&] { done = true; });
  EXPECT_FALSE(done) << "shutdown went on without stopping the fan";
  const std::size_t mark = sent_.size();
  run(d, 3000ms, 10);
  EXPECT_EQ(set_values_from(mark), std::vector<std::uint16_t>{0});
  EXPECT_EQ(fan_.set_value, 0);
  EXPECT_TRUE(done);
}

// That run does not survive a reload that changes the device (docs/profiles.md, "A trip stops
// it"): the new driver finds the fan tripped with its set value not 0, and stops it, as at any
// start.
TEST_F(ReloadOwedStop, ARunAskedInATripDoesNotOutliveAReload) {
  auto old = run_with_its_trip_shown();
  auto next = build(config(250ms));
  Device& fresh = reload(*old, *next, "fan");
  const std::size_t mark = sent_.size();
  run(fresh, 2000ms, 20);
  ASSERT_TRUE(fresh.online());
  EXPECT_EQ(set_values_from(mark), std::vector<std::uint16_t>{0});
  EXPECT_EQ(fan_.set_value, 0);
  EXPECT_EQ(fresh.state().command, Command::stop);
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_reload_owed_stop_test
