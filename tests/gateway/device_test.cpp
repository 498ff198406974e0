// A device's Modbus side: reads from the image, writes validated, judged whole by the driver, then
// applied part by part and answered only when the driver settles them; comm_lost and deadlines
// turn into 0x0B. The device is driven here through its Station calls, as the engine drives it.
#include "gateway/device.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <cmath>

#include "fake_adapter.h"

namespace drivegate {
namespace {

class DeviceTest : public ::testing::Test {
 protected:
  DeviceTest() {
    DeviceConfig cfg;
    cfg.name = "dev";
    cfg.unit_id = 1;
    auto driver = std::make_unique<test::FakeDriver>(DeviceEnv{});
    driver->traits_.comm_timeout = Millis(1000);
    driver->traits_.write_timeout = Millis(500);
    fake_ = driver.get();
    device_ = std::make_unique<Device>(
        cfg, test::kFakeAdapter, std::move(driver),
        std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>()),
        t0_);
  }
  // Every right, the map's word order, unless a test says otherwise.
  Session session_{AccessLevel::maintain, WordOrder::big};
  std::vector<std::uint16_t> input(std::uint16_t address, std::size_t n, TimePoint at) {
    std::vector<std::uint16_t> out(n);
    EXPECT_EQ(device_->read(session_, Table::input, address, out, at), Outcome::ok);
    return out;
  }
  std::vector<std::uint16_t> holding(std::uint16_t address, std::size_t n) {
    std::vector<std::uint16_t> out(n);
    EXPECT_EQ(device_->read(session_, Table::holding, address, out, t0_), Outcome::ok);
    return out;
  }
  // A write as the Modbus server makes it, then the write turn the engine gives the device.
  Outcome write(Table t, std::uint16_t address, std::vector<std::uint16_t> v,
                std::optional<Outcome>& answer) {
    const Outcome result = device_->write(
        session_, t, address, v, [&answer](Outcome e) { answer = e; }, t0_);
    device_->next_exchange(t0_, Turn::write);
    return result;
  }
  // The driver settles the write it was given last; the device learns it at its next call, and
  // the engine's next write turn hands the driver the next part, if any.
  void complete(WriteResult r, TimePoint at) {
    fake_->completions.push_back({fake_->last_ticket, r});
    device_->next_exchange(at, Turn::poll);
    device_->next_exchange(at, Turn::write);
  }
  // A reply carrying the drive's state.
  void heard(TimePoint at) { device_->link().health.data_good(at, at); }

  TimePoint t0_ = TimePoint{} + std::chrono::hours(1);
  test::FakeDriver* fake_;
  std::unique_ptr<Device> device_;
};

TEST_F(DeviceTest, CommonBlockReflectsTheDriver) {
  fake_->common_.ready = true;
  fake_->common_.running = true;
  fake_->common_.speed_rpm = -800;
  fake_->common_.native_fault = 0x48;
  fake_->common_.faults.set(Fault::stall);
  fake_->common_.faults.set(Fault::phase_loss);
  heard(t0_);
  device_->link().counters.frames_good = 1;
  const auto r = input(0, 19, t0_ + Millis(250));
  EXPECT_EQ(r[0], 0b0000'0111);                                    // online, running, fault
  EXPECT_EQ(r[1], static_cast<std::uint16_t>(Fault::phase_loss));  // the more severe
  EXPECT_EQ((std::uint32_t{r[2]} << 16) | r[3], (1u << 7) | (1u << 8));
  EXPECT_EQ(r[5], 0x48);
  EXPECT_EQ(r[6], static_cast<std::uint16_t>(-800));
  EXPECT_EQ((std::uint32_t{r[7]} << 16) | r[8], 250u);  // data age
  EXPECT_EQ(r[10], 1u);                                 // frames good
}

TEST_F(DeviceTest, BusCountersShowInEveryDeviceOnTheBus) {
  BusCounters bus{.exchanges = 70000,
                  .timeouts = 3,
                  .retries = 2,
                  .echo_errors = 4,
                  .noise_bytes = 5,
                  .reopens = 6};
  device_->link().bus = &bus;
  device_->link().counters.foreign = 7;
  const auto r = input(19, 12, t0_);
  EXPECT_EQ((std::uint32_t{r[0]} << 16) | r[1], 70000u);
  EXPECT_EQ(r[3], 3);
  EXPECT_EQ(r[5], 4);
  EXPECT_EQ(r[7], 5);
  EXPECT_EQ(r[9], 6);
  EXPECT_EQ(r[11], 7);
}

TEST_F(DeviceTest, DataAgeSaysNeverBeforeTheFirstFrame) {
  const auto r = input(7, 2, t0_);
  EXPECT_EQ(r[0], 0xFFFF);
  EXPECT_EQ(r[1], 0xFFFF);
}

TEST_F(DeviceTest, AdapterPointsAreScaledIntoTheImage) {
  fake_->values_[0] = -12.3;  // 0.1 degC steps
  fake_->values_[2] = 1.0;
  device_->next_exchange(t0_, Turn::poll);
  const auto r = input(32, 3, t0_);
  EXPECT_EQ(r[0], static_cast<std::uint16_t>(-123));
  EXPECT_EQ(r[1], 0x3F80);
  EXPECT_EQ(r[2], 0x0000);
}

TEST_F(DeviceTest, ReadsOfUnmappedAddressesAreRefused) {
  std::vector<std::uint16_t> out(2);
  EXPECT_EQ(device_->read(session_, Table::input, 30, out, t0_), Outcome::no_such_point);
  EXPECT_EQ(device_->read(session_, Table::holding, 3, out, t0_), Outcome::no_such_point);
  EXPECT_EQ(device_->read(session_, Table::coil, 0, out, t0_), Outcome::no_such_point);
}

TEST_F(DeviceTest, WriteIsAnsweredWhenTheDriverConfirms) {
  std::optional<Outcome> answer;
  ASSERT_EQ(write(Table::holding, 0, {1}, answer), Outcome::ok);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::run_forward});
  EXPECT_FALSE(answer);
  EXPECT_TRUE(input(0, 1, t0_)[0] & (1u << 6));  // command_pending
  EXPECT_EQ(device_->writes_in_flight(), 1u);
  complete(WriteResult::ok, t0_);
  EXPECT_EQ(answer, Outcome::ok);
  EXPECT_FALSE(input(0, 1, t0_)[0] & (1u << 6));
}

TEST_F(DeviceTest, RefusalAndSilenceBecomeExceptions) {
  std::optional<Outcome> a1, a2;
  write(Table::holding, 0, {0}, a1);
  complete(WriteResult::refused, t0_);
  EXPECT_EQ(a1, Outcome::refused);
  write(Table::holding, 0, {0}, a2);
  device_->on_tick(t0_ + Millis(400));
  EXPECT_FALSE(a2);
  device_->on_tick(t0_ + Millis(501));  // write_timeout passed
  EXPECT_EQ(a2, Outcome::no_response);
}

TEST_F(DeviceTest, ValidationComesFirst) {
  std::optional<Outcome> a;
  EXPECT_EQ(write(Table::holding, 3, {1}, a), Outcome::no_such_point);      // unmapped
  EXPECT_EQ(write(Table::holding, 0, {9}, a), Outcome::invalid_value);      // no such command
  EXPECT_EQ(write(Table::holding, 16, {0, 5}, a), Outcome::invalid_value);  // limit < 10
  EXPECT_EQ(write(Table::holding, 17, {5}, a), Outcome::no_such_point);     // mid-point
  EXPECT_EQ(write(Table::holding, 16, {0}, a), Outcome::no_such_point);     // half a u32
  EXPECT_EQ(write(Table::input, 0, {0}, a), Outcome::no_such_point);        // read-only
  EXPECT_EQ(fake_->checks, 0);
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_TRUE(fake_->writes.empty());
  EXPECT_FALSE(a);
}

TEST_F(DeviceTest, DriverRefusalIsAnsweredAtOnce) {
  fake_->check_answer = WriteCheck::invalid_value;
  std::optional<Outcome> a;
  EXPECT_EQ(write(Table::holding, 0, {2}, a), Outcome::invalid_value);
  fake_->check_answer = WriteCheck::refused;
  EXPECT_EQ(write(Table::holding, 0, {2}, a), Outcome::refused);
  EXPECT_TRUE(fake_->commands.empty());  // judged, never applied
  EXPECT_FALSE(a);
}

TEST_F(DeviceTest, SetpointAppliesBeforeTheCommandInOneRequest) {
  std::optional<Outcome> a;
  ASSERT_EQ(write(Table::holding, 0, {1, 1200}, a), Outcome::ok);
  EXPECT_EQ(fake_->setpoints, std::vector<std::int32_t>{1200});
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::run_forward});
  EXPECT_EQ(holding(0, 2)[1], 1200);
}

// FC 0x10 writing command = run_reverse and setpoint_rpm = 1500 to a drive that cannot reverse:
// the whole request is refused and the setpoint is not touched.
TEST_F(DeviceTest, ARequestTheDriverRefusesChangesNothing) {
  fake_->refuse_command = Command::run_reverse;
  std::optional<Outcome> a;
  EXPECT_EQ(write(Table::holding, 0, {2, 1500}, a), Outcome::refused);
  EXPECT_TRUE(fake_->setpoints.empty());
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_EQ(holding(0, 2)[1], 0);
  EXPECT_FALSE(a);
}

// The command goes to the driver only once the setpoint before it settled; a setpoint the drive
// did not take ends the request: the run is never sent.
TEST_F(DeviceTest, PartsApplyOneAfterTheOtherAndAFailureStopsTheRest) {
  fake_->setpoint_answer = WriteStatus::pending;
  std::optional<Outcome> a;
  ASSERT_EQ(write(Table::holding, 0, {1, 1200}, a), Outcome::ok);
  EXPECT_EQ(fake_->setpoints, std::vector<std::int32_t>{1200});
  EXPECT_TRUE(fake_->commands.empty());  // waits for the setpoint
  complete(WriteResult::no_response, t0_);
  EXPECT_EQ(a, Outcome::no_response);
  EXPECT_TRUE(fake_->commands.empty());

  std::optional<Outcome> b;
  ASSERT_EQ(write(Table::holding, 0, {1, 900}, b), Outcome::ok);
  complete(WriteResult::ok, t0_);  // the setpoint
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::run_forward});
  EXPECT_FALSE(b);
  complete(WriteResult::refused, t0_);  // the run, after the setpoint took effect
  EXPECT_EQ(b, Outcome::refused);
  EXPECT_EQ(holding(0, 2)[1], 900);  // what the drive holds
}

TEST_F(DeviceTest, AdapterHoldingPointGoesToTheDriverDecoded) {
  fake_->answer = WriteStatus::done;
  std::optional<Outcome> a;
  ASSERT_EQ(write(Table::holding, 16, {0x0001, 0x86A0}, a), Outcome::ok);
  EXPECT_EQ(a, Outcome::ok);
  ASSERT_EQ(fake_->writes.size(), 1u);
  EXPECT_EQ(fake_->writes[0].first, 1u);
  EXPECT_EQ(std::get<std::int64_t>(fake_->writes[0].second), 100000);
}

// --- listeners: word order and access levels -------------------------------------------

TEST_F(DeviceTest, ALittleEndianSessionReadsEach32BitValueLowWordFirstEvenInPart) {
  fake_->values_[2] = 1.0;  // pressure, f32 at input 33..34: 0x3F80 0x0000 in the map's order
  device_->next_exchange(t0_, Turn::poll);
  session_.word_order = WordOrder::little;
  auto r = input(32, 3, t0_);
  EXPECT_EQ(r[0], static_cast<std::uint16_t>(0));  // i16: never reordered
  EXPECT_EQ(r[1], 0x0000);
  EXPECT_EQ(r[2], 0x3F80);
  EXPECT_EQ(input(34, 1, t0_)[0], 0x3F80);  // the high word lives at the second address
  EXPECT_EQ(input(33, 1, t0_)[0], 0x0000);
  // The common block's 32-bit counters too (data_age_ms at 7..8: never heard = all ones, so use
  // fault_mask at 2..3 with a fault bit in its low word).
  fake_->common_.faults.set(Fault::over_current);
  device_->next_exchange(t0_, Turn::poll);
  const auto mask = input(2, 2, t0_);
  session_.word_order = WordOrder::big;
  const auto big = input(2, 2, t0_);
  EXPECT_EQ(mask[0], big[1]);
  EXPECT_EQ(mask[1], big[0]);
  EXPECT_NE(big[1], 0);
}

TEST_F(DeviceTest, ALittleEndianSessionWrites32BitValuesLowWordFirst) {
  fake_->answer = WriteStatus::done;
  session_.word_order = WordOrder::little;
  std::optional<Outcome> a;
  ASSERT_EQ(write(Table::holding, 16, {0x86A0, 0x0001}, a), Outcome::ok);
  ASSERT_EQ(fake_->writes.size(), 1u);
  EXPECT_EQ(std::get<std::int64_t>(fake_->writes[0].second), 100000);
  // Range checks see the value, not the words: 0x0005'0000 little = 5, below the minimum of 10.
  EXPECT_EQ(write(Table::holding, 16, {0x0005, 0x0000}, a), Outcome::invalid_value);
}

TEST_F(DeviceTest, OperateMayWriteTheCommandBlockButNotAdapterPoints) {
  fake_->answer = WriteStatus::done;
  session_.access = AccessLevel::operate;
  std::optional<Outcome> a;
  EXPECT_EQ(write(Table::holding, 1, {1200}, a), Outcome::ok);  // setpoint_rpm
  EXPECT_EQ(write(Table::holding, 2, {7}, a), Outcome::ok);     // heartbeat
  EXPECT_EQ(write(Table::holding, 0, {1}, a), Outcome::ok);     // command run_forward
  EXPECT_EQ(write(Table::holding, 16, {0x0001, 0x86A0}, a), Outcome::denied);
  // A request reaching one maintain point is refused whole: the setpoint before it stays.
  const auto setpoints = fake_->setpoints.size();
  EXPECT_EQ(write(Table::holding, 1, {900}, a), Outcome::ok);
  EXPECT_EQ(fake_->setpoints.size(), setpoints + 1);
  EXPECT_TRUE(fake_->writes.empty());
  session_.access = AccessLevel::maintain;
  EXPECT_EQ(write(Table::holding, 16, {0x0001, 0x86A0}, a), Outcome::ok);
  EXPECT_EQ(fake_->writes.size(), 1u);
}

// --- writes by point (the MQTT northbound's DCMD) -----------------------------------------

TEST_F(DeviceTest, WritePointsTakesTheSamePathAsAModbusWrite) {
  const auto* command = device_->map().find("command");
  const auto* setpoint = device_->map().find("setpoint_rpm");
  ASSERT_TRUE(command && setpoint);
  const std::vector<Device::PointWrite> run = {{command, std::int64_t{1}},
                                               {setpoint, std::int64_t{900}}};
  std::optional<Outcome> answer;
  ASSERT_EQ(device_->write_points(
                session_, run, [&answer](Outcome e) { answer = e; }, t0_),
            Outcome::ok);
  device_->next_exchange(t0_, Turn::write);
  // The setpoint first, whatever the order given; answered once the driver settled both.
  EXPECT_EQ(fake_->setpoints, std::vector<std::int32_t>{900});
  EXPECT_FALSE(answer);
  complete(WriteResult::ok, t0_);
  fake_->common_.command = Command::run_forward;
  complete(WriteResult::ok, t0_);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::run_forward});
  EXPECT_EQ(answer, Outcome::ok);
  EXPECT_EQ(holding(0, 2), (std::vector<std::uint16_t>{1, 900}));
}

// A request that stops and runs at once (a DCMD naming command twice: stop, then run_forward) is
// no stop: it waits its turn behind the runs queued before it and drops none of them, where a
// stop would go to the drive at once and drop them.
TEST_F(DeviceTest, ARequestThatStopsAndRunsIsNoStopAndDropsNoQueuedRun) {
  fake_->setpoint_answer = WriteStatus::pending;
  std::optional<Outcome> first;
  std::optional<Outcome> queued;
  ASSERT_EQ(write(Table::holding, 0, {1, 1200}, first), Outcome::ok);  // its setpoint in flight
  ASSERT_EQ(write(Table::holding, 0, {1, 800}, queued), Outcome::ok);  // waits behind it
  const auto* command = device_->map().find("command");
  ASSERT_NE(command, nullptr);
  const std::vector<Device::PointWrite> stop_run = {{command, std::int64_t{0}},
                                                    {command, std::int64_t{1}}};
  std::optional<Outcome> both;
  ASSERT_EQ(device_->write_points(
                session_, stop_run, [&both](Outcome e) { both = e; }, t0_),
            Outcome::ok);
  EXPECT_FALSE(queued) << "the queued run was answered: "
                       << to_string(queued.value_or(Outcome::ok));
  EXPECT_TRUE(fake_->commands.empty()) << "sent past the queue";
  EXPECT_FALSE(both);
  // A plain stop still goes first and drops the queued runs, this one with them.
  const std::vector<Device::PointWrite> stop = {{command, std::int64_t{0}}};
  std::optional<Outcome> stopped;
  device_->write_points(
      session_, stop, [&stopped](Outcome e) { stopped = e; }, t0_);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::stop});
  EXPECT_EQ(queued, Outcome::no_response);
  EXPECT_EQ(both, Outcome::no_response);
}

TEST_F(DeviceTest, WritePointsRefusesValuesItsRegistersCannotHold) {
  fake_->answer = WriteStatus::done;
  const auto* setpoint = device_->map().find("setpoint_rpm");  // i16
  const auto* limit = device_->map().find("limit");            // u32, 10..100000
  std::optional<Outcome> a;
  const auto write1 = [&](const MappedPoint* p, Value v) {
    const std::vector<Device::PointWrite> w = {{p, std::move(v)}};
    const Outcome result = device_->write_points(
        session_, w, [&a](Outcome e) { a = e; }, t0_);
    device_->next_exchange(t0_, Turn::write);
    return result;
  };
  // A Modbus client cannot send 40000 in an i16; nor may a DCMD have it saturate to 32767.
  EXPECT_EQ(write1(setpoint, std::int64_t{40000}), Outcome::invalid_value);
  EXPECT_EQ(write1(setpoint, 1.7), Outcome::invalid_value);  // not a whole rpm
  EXPECT_EQ(write1(device_->map().find("heartbeat"), -1.0), Outcome::invalid_value);
  EXPECT_TRUE(fake_->setpoints.empty());
  EXPECT_EQ(write1(limit, std::int64_t{5}), Outcome::invalid_value);  // below its range
  EXPECT_EQ(write1(limit, std::int64_t{100000}), Outcome::ok);
  ASSERT_EQ(fake_->writes.size(), 1u);
  EXPECT_EQ(std::get<std::int64_t>(fake_->writes[0].second), 100000);
  // Access is the device's rule, as for Modbus: operate may not write an adapter point.
  session_.access = AccessLevel::operate;
  EXPECT_EQ(write1(limit, std::int64_t{200}), Outcome::denied);
  EXPECT_EQ(fake_->writes.size(), 1u);
  // Read-only points are not written at all.
  EXPECT_EQ(write1(device_->map().find("speed_rpm"), std::int64_t{1}), Outcome::no_such_point);
}

// NaN and the infinities never reach a drive, whatever the path: a DCMD's setpoint or heartbeat,
// or a Modbus float register holding their bit patterns (docs/safety.md, "Command authority").
TEST_F(DeviceTest, NaNAndInfinitiesAreRefusedOnEveryWritePath) {
  fake_->answer = WriteStatus::done;
  std::optional<Outcome> a;
  const auto write1 = [&](std::string_view point, Value v) {
    const std::vector<Device::PointWrite> w = {{device_->map().find(point), std::move(v)}};
    return device_->write_points(
        session_, w, [&a](Outcome e) { a = e; }, t0_);
  };
  for (const double bad : {std::nan(""), HUGE_VAL, -HUGE_VAL}) {
    EXPECT_EQ(write1("setpoint_rpm", bad), Outcome::invalid_value);
    EXPECT_EQ(write1("heartbeat", bad), Outcome::invalid_value);
    EXPECT_EQ(write1("command", bad), Outcome::invalid_value);
    EXPECT_EQ(write1("gain", bad), Outcome::invalid_value);
  }
  // Modbus: 0x7FC00000 is a quiet NaN, 0x7F800000 +infinity, 0xFF800000 -infinity.
  for (const int high : {0x7FC0, 0x7F80, 0xFF80}) {
    EXPECT_EQ(write(Table::holding, 18, {static_cast<std::uint16_t>(high), 0x0000}, a),
              Outcome::invalid_value);
  }
  device_->next_exchange(t0_, Turn::write);
  EXPECT_TRUE(fake_->setpoints.empty());
  EXPECT_TRUE(fake_->commands.empty());
  EXPECT_TRUE(fake_->writes.empty());
  EXPECT_EQ(holding(2, 1)[0], 0);  // the heartbeat untouched
  EXPECT_FALSE(a);
  // A finite float goes through.
  EXPECT_EQ(write(Table::holding, 18, {0x3FC0, 0x0000}, a), Outcome::ok);
  ASSERT_EQ(fake_->writes.size(), 1u);
  EXPECT_EQ(std::get<double>(fake_->writes[0].second), 1.5);
}

// Shutdown has begun: no client's write reaches the driver any more, from any northbound; the
// gateway's own stop still does.
TEST_F(DeviceTest, OnceShutdownBeganEveryClientWriteIsRefused) {
  device_->close_to_clients();
  std::optional<Outcome> a;
  EXPECT_EQ(write(Table::holding, 0, {1}, a), Outcome::no_response);
  const std::vector<Device::PointWrite> run = {{device_->map().find("command"), std::int64_t{1}}};
  EXPECT_EQ(device_->write_points(
                session_, run, [](Outcome) {}, t0_),
            Outcome::no_response);
  EXPECT_TRUE(fake_->commands.empty());
  std::optional<Outcome> stopped;
  device_->command(
      Command::stop, [&](Outcome e) { stopped = e; }, t0_);
  EXPECT_EQ(fake_->commands, std::vector<Command>{Command::stop});
}

TEST_F(DeviceTest, AReadSessionReachingTheDeviceIsRefusedEvenTheHeartbeat) {
  // The server refuses a read-only client's writes before the backend; the device holds the
  // same line in case another northbound forgets.
  session_.access = AccessLevel::read;
  std::optional<Outcome> a;
  EXPECT_EQ(write(Table::holding, 2, {7}, a), Outcome::denied);
  EXPECT_EQ(write(Table::holding, 0, {1}, a), Outcome::denied);
  EXPECT_TRUE(fake_->commands.empty());
  // Unmapped and read-only addresses still answer 02 (nothing to authorise there).
  EXPECT_EQ(write(Table::holding, 3, {1}, a), Outcome::no_such_point);
}

TEST_F(DeviceTest, CommLostFailsPendingWritesAndRefusesNewOnes) {
  std::optional<Outcome> a, b;
  write(Table::holding, 0, {1}, a);
  ASSERT_TRUE(device_->link().health.lost_by(t0_ + Millis(1001), Millis(1000)));
  device_->on_comm_lost(t0_ + Millis(1001));
  EXPECT_EQ(a, Outcome::no_response);
  EXPECT_EQ(fake_->comm_losts, 1);
  EXPECT_TRUE(device_->comm_lost());
  EXPECT_EQ(input(0, 2, t0_ + Millis(1001))[0] & (1u << 4), 1u << 4);
  EXPECT_EQ(input(0, 2, t0_ + Millis(1001))[1], static_cast<std::uint16_t>(Fault::comm_lost));
  EXPECT_EQ(write(Table::holding, 0, {1}, b), Outcome::no_response);
  // The heartbeat is the gateway's own register and always takes.
  EXPECT_EQ(write(Table::holding, 2, {7}, b), Outcome::ok);
  EXPECT_EQ(b, Outcome::ok);
  heard(t0_ + Millis(1100));
  EXPECT_FALSE(device_->comm_lost());
}

// The drive's last faults were worse than losing it, but they are stale: fault_code says
// comm_lost while fault_mask and native_fault keep what was last known.
TEST_F(DeviceTest, WhileCommLostFaultCodeSaysSo) {
  fake_->common_.faults.set(Fault::over_current);
  fake_->common_.native_fault = 0x10;
  heard(t0_);
  EXPECT_EQ(input(1, 1, t0_)[0], static_cast<std::uint16_t>(Fault::over_current));
  ASSERT_TRUE(device_->link().health.lost_by(t0_ + Millis(1001), Millis(1000)));
  const auto r = input(0, 6, t0_ + Millis(1001));
  EXPECT_EQ(r[1], static_cast<std::uint16_t>(Fault::comm_lost));
  const std::uint32_t mask = (std::uint32_t{r[2]} << 16) | r[3];
  EXPECT_EQ(mask, (1u << static_cast<unsigned>(Fault::over_current)) |
                      (1u << static_cast<unsigned>(Fault::comm_lost)));
  EXPECT_EQ(r[5], 0x10);
}

// --- What each client read of the fault state (gateway/fault_reads.h), and its runs stamped
// with it (WriteOp::fault_seen): a read of status, fault_code, fault_mask or the fault status bit
// that showed a fault is the client's own, until one of its reads shows none. No other read
// counts, nor another client's.

// A client that keeps its record, as a Modbus connection does.
Session reading_client() {
  return Session{AccessLevel::operate, WordOrder::big, true, {}, std::make_shared<FaultReads>()};
}

class DeviceFaultState : public DeviceTest {
 protected:
  DeviceFaultState() {
    fake_->answer = WriteStatus::done;  // each run applied at once: none waits behind another
    fake_->common_.ready = true;
    heard(t0_);
  }
  void tripped() { fake_->common_.faults.set(Fault::over_current); }
  // A read whose reply the client has before it sends anything more (fault_reads.h).
  void read(const Session& s, Table t, std::uint16_t address, std::size_t n, TimePoint at) {
    std::vector<std::uint16_t> out(n);
    ASSERT_EQ(device_->read(s, t, address, out, at), Outcome::ok);
    s.fault_reads->all_sent();
    s.fault_reads->received();
  }
  // The client asks for run_forward at `at`; what the driver was handed as fault_seen.
  std::optional<TimePoint> run_asked(const Session& s, TimePoint at) {
    const std::uint16_t go = 1;  // run_forward
    EXPECT_EQ(device_->write(
                  s, Table::holding, 0, std::span(&go, 1), [](Outcome) {}, at),
              Outcome::ok);
    device_->next_exchange(at, Turn::write);
    EXPECT_FALSE(fake_->fault_seen.empty());
    return fake_->fault_seen.empty() ? std::nullopt : fake_->fault_seen.back();
  }
};

TEST_F(DeviceFaultState, ARunIsStampedWithTheClientsLastReadOfTheFaultShown) {
  const Session plc = reading_client();
  tripped();
  read(plc, Table::input, 0, 1, t0_ + Millis(100));  // status
  EXPECT_EQ(run_asked(plc, t0_ + Millis(300)), t0_ + Millis(100));
}

TEST_F(DeviceFaultState, EveryRegisterOrBitOfTheFaultStateCounts) {
  tripped();
  const Session by_code = reading_client();
  read(by_code, Table::input, 1, 1, t0_ + Millis(100));  // fault_code
  EXPECT_EQ(run_asked(by_code, t0_ + Millis(200)), t0_ + Millis(100));
  const Session by_mask = reading_client();
  read(by_mask, Table::input, 2, 2, t0_ + Millis(300));  // fault_mask (input 2..3)
  EXPECT_EQ(run_asked(by_mask, t0_ + Millis(400)), t0_ + Millis(300));
  const Session by_bit = reading_client();
  read(by_bit, Table::discrete, 2, 1, t0_ + Millis(500));  // status_fault
  EXPECT_EQ(run_asked(by_bit, t0_ + Millis(600)), t0_ + Millis(500));
  const Session in_a_block = reading_client();
  read(in_a_block, Table::input, 0, 16, t0_ + Millis(700));
  EXPECT_EQ(run_asked(in_a_block, t0_ + Millis(800)), t0_ + Millis(700));
}

TEST_F(DeviceFaultState, AReadOfAnythingElseSeesNoFault) {
  tripped();
  const Session plc = reading_client();
  read(plc, Table::input, 4, 4, t0_ + Millis(100));     // past the fault state: speed and more
  read(plc, Table::discrete, 0, 2, t0_ + Millis(100));  // online, running
  read(plc, Table::holding, 0, 2, t0_ + Millis(100));   // command, setpoint_rpm
  EXPECT_EQ(run_asked(plc, t0_ + Millis(200)), std::nullopt);
}

// Either word of fault_mask alone may read 0 with a fault shown (over_current is bit 4: the high
// word is 0): the client has not read the fault.
TEST_F(DeviceFaultState, HalfOfFaultMaskIsNotTheFaultRead) {
  tripped();
  const Session plc = reading_client();
  read(plc, Table::input, 2, 1, t0_ + Millis(100));
  read(plc, Table::input, 3, 1, t0_ + Millis(100));
  EXPECT_EQ(run_asked(plc, t0_ + Millis(200)), std::nullopt);
}

TEST_F(DeviceFaultState, AReadShowingNoFaultForgetsTheOneSeenBefore) {
  const Session plc = reading_client();
  tripped();
  read(plc, Table::input, 0, 1, t0_ + Millis(100));
  fake_->common_.faults = FaultSet{};
  read(plc, Table::input, 0, 1, t0_ + Millis(200));
  tripped();  // a new trip, not read
  EXPECT_EQ(run_asked(plc, t0_ + Millis(300)), std::nullopt);
}

// Two equal runs queued one after the other are joined into one request, unless one was asked
// with the fault in view and the other not: each is then applied with its own.
TEST_F(DeviceFaultState, RunsAskedWithAndWithoutTheFaultInViewAreNotJoined) {
  tripped();
  fake_->answer = WriteStatus::pending;
  const Session reader = reading_client();
  const Session other = reading_client();
  read(reader, Table::input, 0, 1, t0_ + Millis(100));
  const std::uint16_t go = 1;                           // run_forward
  for (const Session* s : {&other, &other, &reader}) {  // the first with the driver, two queued
    EXPECT_EQ(device_->write(
                  *s, Table::holding, 0, std::span(&go, 1), [](Outcome) {}, t0_ + Millis(200)),
              Outcome::ok);
    device_->next_exchange(t0_ + Millis(200), Turn::write);
  }
  complete(WriteResult::ok, t0_ + Millis(300));
  complete(WriteResult::ok, t0_ + Millis(400));
  EXPECT_EQ(fake_->fault_seen,
            (std::vector<std::optional<TimePoint>>{std::nullopt, std::nullopt, t0_ + Millis(100)}));
}

TEST_F(DeviceFaultState, WhatOneClientReadIsNotAnothers) {
  tripped();
  const Session reader = reading_client();
  const Session other = reading_client();
  read(reader, Table::input, 0, 1, t0_ + Millis(100));
  EXPECT_EQ(run_asked(other, t0_ + Millis(200)), std::nullopt);
  const Session no_record{AccessLevel::operate, WordOrder::big};  // MQTT's, the gateway's own
  std::vector<std::uint16_t> status(1);
  ASSERT_EQ(device_->read(no_record, Table::input, 0, status, t0_ + Millis(300)), Outcome::ok);
  EXPECT_EQ(run_asked(no_record, t0_ + Millis(400)), std::nullopt);
}

TEST(LinkHealth, ASilentDeviceIsBackedOffButProbed) {
  const TimePoint t0 = TimePoint{} + std::chrono::hours(1);
  LinkPolicy policy;
  policy.poll_interval = Millis(500);
  policy.backoff_max = Millis(5000);
  LinkHealth h(t0);
  h.turn_failed(t0, policy);
  EXPECT_FALSE(h.in_backoff(t0));  // one miss is not a pattern
  h.turn_failed(t0, policy);
  EXPECT_TRUE(h.in_backoff(t0 + Millis(400)));
  EXPECT_FALSE(h.in_backoff(t0 + Millis(1001)));
  for (int i = 0; i < 20; ++i) h.turn_failed(t0, policy);
  EXPECT_TRUE(h.in_backoff(t0 + Millis(4999)));
  EXPECT_FALSE(h.in_backoff(t0 + Millis(5001)));  // backoff_max
  h.frame_good(t0);
  EXPECT_FALSE(h.in_backoff(t0));
}

}  // namespace
}  // namespace drivegate
