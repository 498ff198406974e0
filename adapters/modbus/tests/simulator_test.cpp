// The example VFD's device and its simulator on the real bus engine with a simulated clock and
// line (tests/support/adapter_bench.h): what a PLC reads and what its writes do to the drive.
#include <gtest/gtest.h>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "common_block.h"
#include "late_reply_contract.h"
#include "profile_support.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;
using test::LateReplyContract;

// Late replies (late_reply_contract.h): a reply timeout of 100 ms (the example's) plus the
// reply's time on the wire at 19200 baud, answered 130 ms late.
const test::LateReplyFacts kLate{.id = "modbus", .late = 130ms};
INSTANTIATE_TEST_SUITE_P(Modbus, LateReplyContract, testing::Values(kLate));

TEST(ModbusOnTheBus, ARunReachesTheSlaveAndItsSpeedTheRegisters) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  EXPECT_EQ(b.read("speed_rpm"), 0u);
  ASSERT_TRUE(b.run_forward_at(1200));
  EXPECT_TRUE(b.until_reads("speed_rpm", 1200, 2000ms));
  EXPECT_EQ(b.read("command"), cmd::run_forward);
  // The status word, read after the speed in each cycle, shows the run bit.
  EXPECT_TRUE(b.rig.run_until([&] { return (b.status() & kRunning) != 0; }, 2s));
  // The slave holds the profile's values: control word 0x000F, reference 1200, speed 12000 x 0.1.
  EXPECT_NE(b.control("state").find("running forward"), std::string::npos);
  EXPECT_NE(b.control("state").find("control_word = 15"), std::string::npos) << b.control("state");
  EXPECT_NE(b.control("state").find("speed_reference = 1200"), std::string::npos);
  EXPECT_EQ(b.write({cmd::stop}), Outcome::ok);
  EXPECT_TRUE(b.until_reads("speed_rpm", 0, 2000ms));
}

TEST(ModbusOnTheBus, ANativeFaultIsTheProfilesUnifiedFault) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.control("fault 3").rfind("ok", 0), 0u);  // 3 = over_voltage in the example's map
  EXPECT_TRUE(b.until_reads("fault_code", static_cast<std::uint32_t>(Fault::over_voltage), 2000ms));
  EXPECT_NE(b.status() & kFaulted, 0u);
  // A run is refused by the tripped drive only in the sense that it does not start: the write is
  // taken (the slave echoes it) and the drive stays stopped.
  ASSERT_EQ(b.control("fault 0").rfind("ok", 0), 0u);
  EXPECT_TRUE(b.until_reads("fault_code", 0, 2000ms));
}

// `run`: the drive run from its own terminals, not over the line (the library test runs the
// profiles that bind no run command so). The PLC sees it run at its setpoint and stop; a faulted
// drive does not start.
TEST(ModbusOnTheBus, ADriveRunFromItsTerminalsShowsItsSpeed) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  ASSERT_EQ(b.write({700}, kSetpointRegister), Outcome::ok);
  ASSERT_EQ(b.control("run reverse"), "ok run reverse");
  EXPECT_TRUE(b.until_reads("speed_rpm", static_cast<std::uint16_t>(-700), 2000ms));
  EXPECT_TRUE(b.rig.run_until([&] { return (b.status() & kRunning) != 0; }, 2s));
  ASSERT_EQ(b.control("run off"), "ok run off");
  EXPECT_TRUE(b.until_reads("speed_rpm", 0, 2000ms));
  ASSERT_EQ(b.control("fault 3").rfind("ok", 0), 0u);
  EXPECT_EQ(b.control("run forward").rfind("error: the drive is faulted", 0), 0u);
  EXPECT_EQ(b.control("run sideways").rfind("error", 0), 0u);
}

TEST(ModbusOnTheBus, ARegisterTheSlaveLacksCostsOnePointNotTheDevice) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_EQ(b.control("missing input 202").rfind("ok", 0), 0u);
  ASSERT_TRUE(b.until_online(1000ms));
  ASSERT_TRUE(b.run_forward_at(900));
  EXPECT_TRUE(b.until_reads("speed_rpm", 900, 3000ms));  // input 200, read alone now
  EXPECT_EQ(b.status() & kCommLost, 0u);
}

TEST(ModbusOnTheBus, AnExceptionFromTheSlaveIs0x04AtThePlc) {
  test::AdapterBench b(drivegate_adapter);
  ASSERT_TRUE(b.until_online());
  // The slave lacks the control word now: a run is answered with exception 02.
  ASSERT_EQ(b.control("missing holding 0").rfind("ok", 0), 0u);
  EXPECT_EQ(b.write({cmd::run_forward, 1000}), Outcome::refused);
  EXPECT_EQ(b.read("command"), cmd::stop);
}

// A profile's access per point reaches the register map: operate opens a holding register to an
// operate client, read keeps one read-only for everyone, and the default is maintain's.
TEST(ModbusOnTheBus, APointsAccessInTheProfileIsTheAccessAtThePlc) {
  const support::ProfileFile file(
      "[profile]\nname = \"access\"\nsource = \"a test\"\n"
      "[[point]]\nname = \"trim\"\ntable = \"holding\"\naddress = 10\n"
      "type = \"u16\"\naccess = \"operate\"\n"
      "[[point]]\nname = \"limit\"\ntable = \"holding\"\naddress = 11\n"
      "type = \"u16\"\n"
      "[[point]]\nname = \"serial\"\ntable = \"holding\"\naddress = 12\n"
      "type = \"u16\"\naccess = \"read\"\n",
      "access.toml");
  test::BusRig rig(drivegate_adapter);
  Device& d = rig.add_device("d", 7, {{"profile", file.path}});
  rig.add_simulator(7, {{"profile", file.path}});
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return d.online(); }, 3s));
  const auto at = [&](std::string_view name) { return d.map().find(name)->address; };
  const Session operate{AccessLevel::operate, drivegate::WordOrder::big};
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, at("trim"), {5}, 3s, operate), Outcome::ok);
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, at("limit"), {5}, 3s, operate), Outcome::denied);
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, at("limit"), {5}, 3s), Outcome::ok);  // maintain
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, at("serial"), {5}, 3s),
            Outcome::no_such_point);  // read-only even for maintain: exception 02
  EXPECT_EQ(rig.read(d, Table::holding, at("serial"), 1).size(), 1u);  // and still read
}

}  // namespace
}  // namespace drivegate::modbus_device
