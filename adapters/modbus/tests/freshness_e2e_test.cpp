// A profile device tells the truth end to end: the real daemon polls `drivegate sim modbus`
// (example-vfd, address 1, on a pty) for a PLC reading over Modbus TCP. The slave refuses its
// status word once (busy) and the drive then trips: the PLC reads the trip, not the last status
// with a fresh data age. The status word then goes unanswered: the data age grows while the other
// blocks answer, and the device goes comm_lost; answered again, it is back.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

std::string config(const std::string& port) {
  return "[[bus]]\nname = \"line-a\"\nport = \"" + port +
         "\"\nbaud = 19200\nparity = \"even\"\n\n"
         "[[device]]\nname = \"fan-1\"\nbus = \"line-a\"\nadapter = \"modbus\"\nunit_id = 1\n"
         "address = 1\npoll_ms = 200\n[device.options]\nprofile = \"example-vfd\"\n";
}

bool ok(const std::string& answer) {
  return answer.rfind("ok", 0) == 0;
}

TEST(ModbusFreshnessE2E, ARefusedOrSilentStatusWordNeverHidesATrip) {
  TempDir dir;
  Sim sim("modbus", dir / "tty-a", {"--set", "profile=example-vfd", "--address", "1"});
  Daemon daemon(dir, config((dir / "tty-a").string()), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  const auto status = [&] { return plc.input(reg::status, 1).regs.at(0); };
  const auto age = [&] { return plc.input(reg::data_age, 2).u32(0); };
  ASSERT_TRUE(eventually([&] { return (status() & reg::online) != 0; }, 10s))
      << slurp(dir / "drivegated.log");
  ASSERT_EQ(plc.write(reg::command, {1, 1000}), 0);
  ASSERT_TRUE(eventually([&] { return (status() & reg::running) != 0; }, 5s));

  // Refused once (exception 06), then the trip: shown within a few cycles.
  ASSERT_TRUE(ok(sim.control("refuse holding 100 6")));
  std::this_thread::sleep_for(600ms);
  ASSERT_TRUE(ok(sim.control("fault 2")));
  // The status word and the fault code are two reads of a cycle, published together: read in
  // one request, the fault bit never stands without its code (over_current, 4; never 17, other).
  std::vector<std::uint16_t> seen;
  EXPECT_TRUE(eventually(
      [&] {
        const auto both = plc.input(reg::status, 2).regs;
        if ((both.at(0) & reg::fault) != 0) seen.push_back(both.at(1));
        return (both.at(0) & (reg::fault | reg::running)) == reg::fault;
      },
      5s))
      << "status " << status() << ", data age " << age();
  ASSERT_FALSE(seen.empty());
  for (const std::uint16_t code : seen) EXPECT_EQ(code, 4) << "a fault read with code " << code;
  EXPECT_LT(age(), 2000u);

  // Unanswered from now on: the data age grows past a second, then comm_lost (3 s).
  ASSERT_TRUE(ok(sim.control("fault 0")));
  ASSERT_TRUE(ok(sim.control("mute holding 100 on")));
  EXPECT_TRUE(eventually([&] { return age() >= 1500; }, 5s)) << "data age " << age();
  EXPECT_TRUE(eventually([&] { return (status() & reg::comm_lost) != 0; }, 10s));
  EXPECT_EQ(plc.input(reg::fault_code, 1).regs.at(0), 1);  // comm_lost
  ASSERT_TRUE(ok(sim.control("mute holding 100 off")));
  EXPECT_TRUE(
      eventually([&] { return (status() & (reg::online | reg::comm_lost)) == reg::online; }, 10s));
  EXPECT_LT(age(), 2000u);
  EXPECT_EQ(daemon.stop(), 0);
}

}  // namespace
}  // namespace drivegate::test
