// The driver against the simulator on a simulated bus (tests/support/loopback.h).
#include "driver.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "faults.h"
#include "loopback.h"
#include "simulator.h"

namespace drivegate::nidec {
namespace {

using namespace std::chrono_literals;

const Bytes kPoll = {0xA5, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0};    // 5.2
const Bytes kStop = {0xA5, 0x27, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x82};    // 5.7
const Bytes kBrake = {0xA5, 0x29, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8C};   // 5.8
const Bytes kPing7 = {0xA5, 0x02, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xA0};   // 5.1
const Bytes kCw800 = {0xA5, 0x09, 0x03, 0x20, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x91};   // 5.3
const Bytes kCcw800 = {0xA5, 0x0B, 0x03, 0x20, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x93};  // 5.4
const Bytes kFct = {0xA5, 0x66, 0x12, 0x00, 0x34, 0x00, 0x56, 0x00, 0x78, 0x00, 0xCB};     // 5.15

class Bench : public ::testing::Test {
 protected:
  explicit Bench(DriverConfig c = {}) : driver(c), sim(SimEnv{}), bus(driver, sim) {}

  std::int64_t integer(std::size_t p) const { return std::get<std::int64_t>(driver.values()[p]); }
  double real(std::size_t p) const { return as_double(driver.values()[p]); }

  void start() {
    ASSERT_TRUE(bus.run_until([&] { return driver.common().ready; }, 1s));
  }

  // Waits for the completion of `t`; nullopt if none came within `limit`.
  std::optional<WriteResult> outcome(Ticket t, Millis limit = 3s) {
    std::optional<WriteResult> r;
    bus.run_until(
        [&] {
          for (const Completion& c : bus.completions) {
            if (c.ticket == t) r = c.result;
          }
          return r.has_value();
        },
        limit);
    return r;
  }

  WriteResult issue(Command c) {
    const Ticket t = next++;
    EXPECT_EQ(driver.command(c, t, bus.now()), WriteStatus::pending);
    return outcome(t).value_or(WriteResult::no_response);
  }

  WriteResult act(Action a) {
    const Ticket t = next++;
    EXPECT_EQ(driver.write(pt::action, std::int64_t{static_cast<std::int64_t>(a)}, t, bus.now()),
              WriteStatus::pending);
    return outcome(t).value_or(WriteResult::no_response);
  }

  WriteStatus set(std::size_t p, Value v) { return driver.write(p, v, next++, bus.now()); }

  std::size_t mark() const { return bus.sent.size(); }
  std::vector<Bytes> since(std::size_t m) const {
    return {bus.sent.begin() + static_cast<long>(m), bus.sent.end()};
  }

  WasherDriver driver;
  WasherSimulator sim;
  test::Loopback bus;
  Ticket next = 1;
};

TEST_F(Bench, PingsFirstThenPollsEvery500ms_5_1_section6) {
  bus.run_for(1900ms);
  ASSERT_EQ(bus.sent.size(), 4u);  // t = 0, 500, 1000, 1500 ms
  EXPECT_EQ(bus.sent[0], kPing7);
  for (std::size_t i = 1; i < bus.sent.size(); ++i) EXPECT_EQ(bus.sent[i], kPoll) << i;
  EXPECT_TRUE(driver.common().ready);
  EXPECT_EQ(integer(pt::inverter_version), 0x0107);
  EXPECT_EQ(integer(pt::platform), 7);
  EXPECT_EQ(driver.traits().comm_timeout, 6000ms);
}

TEST(NidecDriver, ExchangeTimingAndOptions) {
  Options o({{"platform", std::int64_t{8}},
             {"empty_raw_weight", std::int64_t{0x012C}},
             {"accel_time_ms", std::int64_t{5000}},
             {"attempts", std::int64_t{4}}});
  DeviceEnv env;
  env.options = o;
  env.poll_interval = 5000ms;  // section 6: at least every second
  const DriverConfig c = config_from(env);
  EXPECT_EQ(c.poll_interval, 1000ms);
  EXPECT_EQ(c.accel_100ms, 50);
  WasherDriver d(c);
  const std::optional<Exchange> ex = d.next_exchange(TimePoint{});
  ASSERT_TRUE(ex);
  EXPECT_EQ(ex->frame, (Bytes{0xA5, 0x02, 0x08, 0x01, 0x2C, 0x00, 0x00, 0x00, 0x00, 0x00, 0x82}));
  EXPECT_EQ(ex->timeout, 100ms);  // section 6: resend after 100 ms
  EXPECT_EQ(ex->attempts, 4);
  EXPECT_EQ(ex->reply, ReplyMode::expected);
  EXPECT_DOUBLE_EQ(as_double(d.values()[pt::accel_time]), 5.0);
}

TEST_F(Bench, CommandBeforeHandshakeWaitsForThePing) {
  EXPECT_EQ(driver.setpoint(800, next++, bus.now()), WriteStatus::done);
  const Ticket t = next++;
  ASSERT_EQ(driver.command(Command::run_forward, t, bus.now()), WriteStatus::pending);
  EXPECT_EQ(outcome(t), WriteResult::ok);
  ASSERT_GE(bus.sent.size(), 2u);
  EXPECT_EQ(bus.sent[0], kPing7);
  EXPECT_EQ(bus.sent[1], kCw800);
}

TEST_F(Bench, RunForwardIsCwAtTheSetpoint_5_3) {
  start();
  EXPECT_EQ(driver.setpoint(800, next++, bus.now()), WriteStatus::done);
  const std::size_t m = mark();
  EXPECT_EQ(issue(Command::run_forward), WriteResult::ok);
  EXPECT_EQ(since(m).front(), kCw800);
  EXPECT_EQ(driver.common().command, Command::run_forward);
  EXPECT_TRUE(driver.common().running);
  bus.run_for(4s);  // 3.0 s accel
  EXPECT_EQ(driver.common().speed_rpm, 800);
  EXPECT_EQ(driver.common().setpoint_rpm, 800);
}

TEST_F(Bench, RunReverseIsCcw_5_4) {
  start();
  driver.setpoint(800, next++, bus.now());
  const std::size_t m = mark();
  EXPECT_EQ(issue(Command::run_reverse), WriteResult::ok);
  EXPECT_EQ(since(m).front(), kCcw800);
  EXPECT_EQ(driver.common().command, Command::run_reverse);
}

TEST_F(Bench, MotionChoosesSpinAgitationOrFreeShaft_5_5_5_6_5_14) {
  start();
  driver.setpoint(1200, next++, bus.now());
  EXPECT_EQ(set(pt::motion, std::int64_t{1}), WriteStatus::done);
  EXPECT_EQ(driver.command(Command::run_reverse, next++, bus.now()), WriteStatus::invalid_value);
  std::size_t m = mark();
  EXPECT_EQ(issue(Command::run_forward), WriteResult::ok);
  EXPECT_EQ(since(m).front(),
            (Bytes{0xA5, 0x0D, 0x04, 0xB0, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x02}));

  EXPECT_EQ(set(pt::motion, std::int64_t{2}), WriteStatus::done);
  driver.setpoint(60, next++, bus.now());  // still spinning: re-sent as spin at 60 rpm
  bus.run_for(200ms);
  m = mark();
  EXPECT_EQ(issue(Command::run_forward), WriteResult::ok);
  EXPECT_EQ(since(m).front(),
            (Bytes{0xA5, 0x0C, 0x00, 0x3C, 0x05, 0x05, 0x0C, 0x08, 0x0C, 0x08, 0x95}));

  EXPECT_EQ(set(pt::motion, std::int64_t{3}), WriteStatus::done);
  EXPECT_EQ(set(pt::accel_time, 5.0), WriteStatus::done);
  driver.setpoint(1500, next++, bus.now());  // agitation in force: re-sent as agitation
  bus.run_for(200ms);
  m = mark();
  EXPECT_EQ(issue(Command::run_forward), WriteResult::ok);
  EXPECT_EQ(since(m).front(),
            (Bytes{0xA5, 0x1D, 0x05, 0xDC, 0x00, 0x32, 0x00, 0x00, 0x00, 0x00, 0x53}));
}

TEST_F(Bench, AgitationTimingPoints_5_5) {
  start();
  EXPECT_EQ(set(pt::motion, std::int64_t{2}), WriteStatus::done);
  EXPECT_EQ(set(pt::agitation_accel, 0.3), WriteStatus::done);
  EXPECT_EQ(set(pt::agitation_decel, 0.4), WriteStatus::done);
  EXPECT_EQ(set(pt::agitation_cw_on, 2.0), WriteStatus::done);
  EXPECT_EQ(set(pt::agitation_cw_off, 1.0), WriteStatus::done);
  EXPECT_EQ(set(pt::agitation_ccw_on, 2.5), WriteStatus::done);
  EXPECT_EQ(set(pt::agitation_ccw_off, 25.5), WriteStatus::done);
  EXPECT_EQ(set(pt::agitation_ccw_off, 25.6), WriteStatus::invalid_value);
  driver.setpoint(100, next++, bus.now());
  const std::size_t m = mark();
  EXPECT_EQ(issue(Command::run_forward), WriteResult::ok);
  Bytes want = {0xA5, 0x0C, 0x00, 0x64, 3, 4, 20, 10, 25, 255};
  want.push_back(xor_of(want));
  EXPECT_EQ(since(m).front(), want);
  EXPECT_DOUBLE_EQ(real(pt::agitation_ccw_on), 2.5);
}

TEST_F(Bench, SetpointWhileRunningIsSentAtOnce) {
  start();
  driver.setpoint(800, next++, bus.now());
  issue(Command::run_forward);
  const Ticket t = next++;
  ASSERT_EQ(driver.setpoint(1000, t, bus.now()), WriteStatus::pending);
  const std::size_t m = mark();
  EXPECT_EQ(outcome(t), WriteResult::ok);
  EXPECT_EQ(since(m).front(),
            (Bytes{0xA5, 0x09, 0x03, 0xE8, 0x00, 0x1E, 0x00, 0x00, 0x00, 0x00, 0x59}));
  EXPECT_EQ(driver.setpoint(-1, next++, bus.now()), WriteStatus::invalid_value);
  EXPECT_EQ(driver.setpoint(70000, next++, bus.now()), WriteStatus::invalid_value);
}

TEST_F(Bench, StopAndQuickStop_5_7_5_8) {
  start();
  driver.setpoint(800, next++, bus.now());
  issue(Command::run_forward);
  bus.run_for(4s);
  std::size_t m = mark();
  EXPECT_EQ(issue(Command::quick_stop), WriteResult::ok);
  EXPECT_EQ(since(m).front(), kBrake);
  EXPECT_EQ(driver.common().command, Command::quick_stop);
  m = mark();
  EXPECT_EQ(issue(Command::stop), WriteResult::ok);
  EXPECT_EQ(since(m).front(), kStop);
  bus.run_for(2s);
  EXPECT_EQ(driver.common().speed_rpm, 0);
  EXPECT_FALSE(driver.common().running);
}

TEST_F(Bench, NackIsResentIdentically_5_16) {
  start();
  sim.control("nack 1", bus.now());
  const std::size_t m = mark();
  EXPECT_EQ(issue(Command::stop), WriteResult::ok);
  const std::vector<Bytes> s = since(m);
  ASSERT_GE(s.size(), 2u);
  EXPECT_EQ(s[0], kStop);
  EXPECT_EQ(s[1], kStop);
  EXPECT_EQ(bus.nacks, 1);
}

TEST_F(Bench, BadChecksumIsResent) {
  start();
  sim.control("corrupt 2", bus.now());
  const std::size_t m = mark();
  EXPECT_EQ(issue(Command::stop), WriteResult::ok);
  const std::vector<Bytes> s = since(m);
  ASSERT_GE(s.size(), 3u);
  EXPECT_EQ(s[0], kStop);
  EXPECT_EQ(s[1], kStop);
  EXPECT_EQ(s[2], kStop);
  EXPECT_EQ(bus.bad_frames, 2);
}

TEST_F(Bench, NoiseAndStaleRepliesAreDropped) {
  start();
  // Noise before the reply, and a stale brake ACK: the poll's ACK still completes the turn.
  bus.line_filter = [](Bytes b) {
    Bytes out = {0x00, 0x13};
    const Bytes stale = encode_reply(Mode::brake, {0, 0, 0, 0});
    out.insert(out.end(), stale.begin(), stale.end());
    out.insert(out.end(), b.begin(), b.end());
    return out;
  };
  const int good = bus.good_frames;
  bus.run_for(1s);
  EXPECT_GE(bus.good_frames, good + 2);
  EXPECT_EQ(bus.timeouts, 0);
  EXPECT_EQ(bus.retries, 0);
}

TEST_F(Bench, SilentDeviceResendsThenWriteFailsThenCommLost_section6) {
  start();
  sim.control("silent on", bus.now());
  const TimePoint t0 = bus.now();
  const Ticket t = next++;
  ASSERT_EQ(driver.command(Command::stop, t, t0), WriteStatus::pending);
  const std::size_t m = mark();
  EXPECT_EQ(outcome(t), WriteResult::no_response);
  EXPECT_LE(bus.now() - t0, 3000ms);  // before the gateway's write_timeout
  const std::vector<Bytes> s = since(m);
  ASSERT_GE(s.size(), 20u);  // about one resend per 100 ms, then polls once it failed
  const auto stops = std::count(s.begin(), s.end(), kStop);
  EXPECT_GE(stops, 20);
  EXPECT_TRUE(std::all_of(s.begin(), s.begin() + stops, [](const Bytes& f) { return f == kStop; }));
  ASSERT_TRUE(bus.run_until([&] { return bus.comm_lost(); }, 7s));
  EXPECT_FALSE(driver.common().ready);

  sim.control("silent off", bus.now());
  const std::size_t r = mark();
  ASSERT_TRUE(bus.run_until([&] { return driver.common().ready; }, 1s));
  EXPECT_EQ(since(r).front(), kPing7);  // 5.1: ping again after a reconnect
  EXPECT_EQ(since(r).back(), kPing7);
}

TEST_F(Bench, CommLostStopsAndDoesNotResumeMotion_section7) {
  start();
  driver.setpoint(800, next++, bus.now());
  issue(Command::run_forward);
  bus.run_for(4s);
  sim.control("silent on", bus.now());
  ASSERT_TRUE(bus.run_until([&] { return bus.comm_lost(); }, 7s));
  EXPECT_EQ(driver.common().command, Command::stop);
  EXPECT_FALSE(driver.common().running);
  sim.control("silent off", bus.now());
  bus.run_for(2s);
  EXPECT_TRUE(driver.common().ready);
  EXPECT_EQ(driver.common().speed_rpm, 0);
  EXPECT_NE(sim.control("state", bus.now()).find("motion=stopped"), std::string::npos);
}

TEST(NidecFaults, BitmaskMapping_section8) {
  EXPECT_TRUE(map_faults(0).empty());
  EXPECT_EQ(map_faults(0x01), FaultSet{1u << static_cast<unsigned>(Fault::internal_error)});
  const std::pair<std::uint8_t, Fault> table[] = {
      {0x01, Fault::internal_error}, {0x02, Fault::drive_over_temperature},
      {0x04, Fault::over_voltage},   {0x08, Fault::stall},
      {0x10, Fault::over_current},   {0x20, Fault::under_voltage},
      {0x40, Fault::phase_loss},     {0x80, Fault::motor_over_temperature}};
  for (const auto& [bit, fault] : table) {
    const FaultSet s = map_faults(bit);
    EXPECT_TRUE(s.has(fault)) << int{bit};
    EXPECT_EQ(s.bits(), 1u << static_cast<unsigned>(fault)) << int{bit};
  }
  const FaultSet all = map_faults(0xFF);
  for (const auto& [bit, fault] : table) EXPECT_TRUE(all.has(fault));
}

TEST_F(Bench, FaultsReachCommonStateAndClearAfter4s_section8) {
  start();
  sim.control("fault 0x18", bus.now());  // stall + over-current
  bus.run_for(600ms);
  EXPECT_EQ(driver.common().native_fault, 0x18u);
  EXPECT_TRUE(driver.common().faults.has(Fault::stall));
  EXPECT_TRUE(driver.common().faults.has(Fault::over_current));
  EXPECT_EQ(most_severe(driver.common().faults), Fault::over_current);
  EXPECT_EQ(integer(pt::error_bits), 0x18);
  EXPECT_EQ(driver.command(Command::run_forward, next++, bus.now()), WriteStatus::refused);
  bus.run_for(4s);
  EXPECT_EQ(driver.common().native_fault, 0u);
  EXPECT_TRUE(driver.common().faults.empty());
  EXPECT_EQ(issue(Command::run_forward), WriteResult::ok);
}

TEST_F(Bench, RunAckedWithErrorIsRefused) {
  start();
  driver.setpoint(800, next++, bus.now());
  sim.control("fault phase_loss", bus.now());  // before any poll shows it
  EXPECT_EQ(issue(Command::run_forward), WriteResult::refused);
  EXPECT_TRUE(driver.common().faults.has(Fault::phase_loss));
  EXPECT_EQ(driver.common().command, Command::stop);
}

TEST_F(Bench, ResetFaultAsksWhetherTheFaultCleared) {
  start();
  sim.control("fault general", bus.now());  // section 8: kept until power off
  bus.run_for(5s);
  std::size_t m = mark();
  EXPECT_EQ(issue(Command::reset_fault), WriteResult::refused);
  EXPECT_EQ(since(m).front(), kPoll);
  EXPECT_TRUE(driver.common().faults.has(Fault::internal_error));
  sim.control("clear", bus.now());
  EXPECT_EQ(issue(Command::reset_fault), WriteResult::ok);
  EXPECT_TRUE(driver.common().faults.empty());
}

TEST_F(Bench, VoltageDetection_5_9) {
  start();
  const std::size_t m = mark();
  EXPECT_EQ(act(Action::voltage_detection), WriteResult::ok);
  EXPECT_EQ(since(m).front(),
            (Bytes{0xA5, 0x2B, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x8E}));
  EXPECT_EQ(integer(pt::dc_bus_voltage), 311);
  EXPECT_EQ(integer(pt::action), 1);
  EXPECT_EQ(integer(pt::action_status), static_cast<std::int64_t>(ActionStatus::done));
}

TEST_F(Bench, WeightDetectionTakes35s_5_10) {
  start();
  EXPECT_EQ(act(Action::weight_detection), WriteResult::ok);
  EXPECT_EQ(integer(pt::raw_weight), 0);
  EXPECT_DOUBLE_EQ(real(pt::weight), 0.0);
  bus.run_for(36s);
  EXPECT_DOUBLE_EQ(real(pt::weight), 3.5);  // 5.2: the Request ACK reports it too
  EXPECT_EQ(act(Action::weight_detection), WriteResult::ok);
  EXPECT_EQ(integer(pt::raw_weight), 1700);
}

TEST_F(Bench, FabricDetectionIsKeptRaw_5_11) {
  start();
  sim.control("fabric 3", bus.now());
  EXPECT_EQ(act(Action::fabric_detection), WriteResult::ok);
  EXPECT_EQ(integer(pt::fabric_raw), 0x00030000);
}

TEST_F(Bench, ForcedBrakeBlocksMotion_5_13) {
  start();
  std::size_t m = mark();
  EXPECT_EQ(act(Action::forced_brake_enable), WriteResult::ok);
  EXPECT_EQ(since(m).front(),
            (Bytes{0xA5, 0x1B, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xBF}));
  EXPECT_EQ(integer(pt::forced_brake), 1);
  EXPECT_EQ(driver.command(Command::run_forward, next++, bus.now()), WriteStatus::refused);
  m = mark();
  EXPECT_EQ(act(Action::forced_brake_disable), WriteResult::ok);
  EXPECT_EQ(since(m).front(),
            (Bytes{0xA5, 0x1B, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0xBE}));
  EXPECT_EQ(integer(pt::forced_brake), 0);
}

TEST_F(Bench, FctTest_5_15) {
  start();
  sim.control("fault stall", bus.now());
  const std::size_t m = mark();
  EXPECT_EQ(act(Action::fct_test), WriteResult::ok);
  EXPECT_EQ(since(m).front(), kFct);
  EXPECT_EQ(integer(pt::fct_error), 0x0008);
  EXPECT_EQ(integer(pt::fct_speed_rpm), 0);
  EXPECT_EQ(integer(pt::fct_ipm_temperature), 45);
  EXPECT_EQ(integer(pt::fct_ipm_model_bus_volt_high), 0x11);
  EXPECT_EQ(integer(pt::fct_bus_volt_low), 0x37);
  EXPECT_EQ(integer(pt::fct_phase_current), 0);
}

TEST_F(Bench, PingAgainOnRequest_5_1) {
  start();
  sim.control("version 0x0203", bus.now());
  const std::size_t m = mark();
  EXPECT_EQ(act(Action::ping), WriteResult::ok);
  EXPECT_EQ(since(m).front(), kPing7);
  EXPECT_EQ(integer(pt::inverter_version), 0x0203);
  EXPECT_EQ(set(pt::action, std::int64_t{0}), WriteStatus::done);
  EXPECT_EQ(set(pt::action, std::int64_t{8}), WriteStatus::invalid_value);
  EXPECT_EQ(set(pt::motion, std::int64_t{4}), WriteStatus::invalid_value);
  EXPECT_EQ(set(pt::dc_bus_voltage, std::int64_t{1}), WriteStatus::invalid_value);
}

TEST_F(Bench, CommLostFailsPendingWrites) {
  start();
  sim.control("silent on", bus.now());
  bus.run_for(5500ms);
  ASSERT_FALSE(bus.comm_lost());
  const Ticket t = next++;
  ASSERT_EQ(driver.command(Command::stop, t, bus.now()), WriteStatus::pending);
  EXPECT_EQ(outcome(t, 1s), WriteResult::no_response);
  EXPECT_TRUE(bus.comm_lost());
}

TEST(NidecDriverPoints, FixedTableWithLabels) {
  WasherDriver d{DriverConfig{}};
  ASSERT_EQ(d.points().size(), pt::count);
  ASSERT_EQ(d.values().size(), pt::count);
  EXPECT_EQ(d.points()[pt::motion].name, "motion");
  EXPECT_EQ(d.points()[pt::motion].table, Table::holding);
  EXPECT_EQ(d.points()[pt::action].labels.size(), 8u);
  EXPECT_TRUE(d.points()[pt::error_bits].bit_labels);
  EXPECT_EQ(d.points()[pt::error_bits].labels[3].name, "stall");
  EXPECT_EQ(d.points()[pt::fabric_raw].register_count(), 2);
  for (const PointSpec& p : d.points()) {
    EXPECT_FALSE(p.description.empty()) << p.name;
    if (p.table == Table::holding) {
      EXPECT_LT(p.min, p.max) << p.name;
    }
  }
}

}  // namespace
}  // namespace drivegate::nidec
