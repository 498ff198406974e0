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

// A washer at unit 1, online, with a PLC connected to the daemon.
class ReloadE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(plc_.connect());
    ASSERT_TRUE(eventually([&] { return online(plc_); }, 10s));
  }
  TempDir dir_;
  Sim sim_{"nidec-washer", dir_ / "washer"};
  Daemon daemon_{dir_, washer(dir_ / "washer", 1)};
  Plc plc_{daemon_.port(), 1};
};

TEST_F(ReloadE2E, GoodConfigSwapsDevicesKeepingConnections) {
  // The same drive moves to unit 2; the open connection sees the change.
  std::ofstream(daemon_.config()) << washer(dir_ / "washer", 2);
  daemon_.process().signal(SIGHUP);
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::status, 1).exception == 0x0A; }, 10s));
  plc_.unit(2);
  EXPECT_TRUE(eventually([&] { return online(plc_); }, 10s));
  EXPECT_TRUE(daemon_.process().running());
}

TEST_F(ReloadE2E, BadConfigIsRefusedAndTheOldOneKeepsServing) {
  std::ofstream(daemon_.config()) << "[[device]]\nname = 5\n";
  daemon_.process().signal(SIGHUP);
  std::this_thread::sleep_for(1s);
  EXPECT_TRUE(daemon_.process().running());
  EXPECT_TRUE(online(plc_));
  EXPECT_EQ(plc_.write(reg::command, {1, 700}), 0);
}

}  // namespace
}  // namespace drivegate::test
