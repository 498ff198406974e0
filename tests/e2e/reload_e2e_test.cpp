// SIGHUP: a good new configuration is applied without dropping a Modbus TCP connection; a bad
// one is refused and the daemon keeps serving the old one.
#include <gtest/gtest.h>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

std::string washer(const std::filesystem::path& port, int unit) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"washer\"\nbus = \"line\"\nadapter = \"nidec-washer\"\n"
         "unit_id = " +
         std::to_string(unit) + "\n";
}

bool online(Plc& plc) {
  const auto r = plc.input(reg::status, 1);
  return r.ok() && (r.regs[0] & reg::online) != 0;
}

TEST(ReloadE2E, GoodConfigSwapsDevicesKeepingConnections) {
  TempDir dir;
  Sim sim("nidec-washer", dir / "washer");
  Daemon daemon(dir, washer(dir / "washer", 1));
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s));

  // The same drive moves to unit 2; the open connection sees the change.
  std::ofstream(daemon.config()) << washer(dir / "washer", 2);
  daemon.process().signal(SIGHUP);
  ASSERT_TRUE(eventually([&] { return plc.input(reg::status, 1).exception == 0x0A; }, 10s));
  plc.unit(2);
  EXPECT_TRUE(eventually([&] { return online(plc); }, 10s));
  EXPECT_TRUE(daemon.process().running());
}

TEST(ReloadE2E, BadConfigIsRefusedAndTheOldOneKeepsServing) {
  TempDir dir;
  Sim sim("nidec-washer", dir / "washer");
  Daemon daemon(dir, washer(dir / "washer", 1));
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s));

  std::ofstream(daemon.config()) << "[[device]]\nname = 5\n";
  daemon.process().signal(SIGHUP);
  std::this_thread::sleep_for(1s);
  EXPECT_TRUE(daemon.process().running());
  EXPECT_TRUE(online(plc));
  EXPECT_EQ(plc.write(reg::command, {1, 700}), 0);
}

}  // namespace
}  // namespace drivegate::test
