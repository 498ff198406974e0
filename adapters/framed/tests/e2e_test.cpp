// framed end to end: the daemon on `drivegate sim framed --set protocol=nidec-washer`, the
// simulator a description makes, driven from Modbus TCP as a PLC would; and the registration
// of framed for the core's scenarios on every drive (capture: the described frames decoded in
// tshark by adapters/framed/dissector.lua). The seed protocols' own scenarios run under framed
// too (tests/support/protocol_adapters.h).
#include "e2e.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "e2e_adapters.h"

namespace drivegate::test::framed_e2e_test {
namespace {

using namespace std::chrono_literals;

const RegisterE2eAdapter kE2eAdapter(
    {.id = "framed",
     .device_extra = "[device.options]\nprotocol = \"nidec-washer\"\nplatform = 8\n",
     .sim_args = {"--set", "protocol=nidec-washer", "--set", "platform=8"},
     .rpm = 800,
     .protocol = "NIDEC-WASHER",
     .checksum_field = "framed_nidec_washer.checksum.status",
     .capture_id = "framed/nidec-washer"});

std::string config(const std::filesystem::path& port, const std::string& protocol_file) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"washer\"\nbus = \"line\"\nadapter = \"framed\"\nunit_id = 1\n"
         "[device.options]\nprotocol = \"" +
         protocol_file + "\"\nplatform = 8\n";
}

class FramedE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(plugin_dir() / "drivegate-framed.so")) GTEST_SKIP();
  }
  TempDir dir_;
};

// The simulator a description makes, the daemon on it: a drive commissioned before hardware.
TEST_F(FramedE2E, TheDescribedSimulatorRunsAndStops) {
  Sim sim("framed", dir_ / "washer", {"--set", "protocol=nidec-washer", "--set", "platform=8"});
  EXPECT_THAT(sim.control("state"), ::testing::HasSubstr("protocol=nidec-washer"));
  Daemon daemon(dir_, config(dir_ / "washer", "nidec-washer"));
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(comes_online(plc)) << sim.control("state");
  ASSERT_EQ(plc.write(reg::command, {1 /*run_forward*/, 800}), 0) << sim.control("state");
  ASSERT_TRUE(eventually([&] { return plc.input(reg::speed, 1).regs[0] == 800; }, 10s))
      << sim.control("state");
  EXPECT_THAT(sim.control("state"), ::testing::HasSubstr("platform=8"));
  // A fault set on the simulator's console is the unified fault, and refuses a run.
  EXPECT_EQ(sim.control("set error_bits 8"), "ok error_bits=8");
  ASSERT_TRUE(eventually([&] { return plc.input(reg::fault_code, 1).regs[0] == 7; }, 5s));
  EXPECT_EQ(plc.input(reg::native_fault, 2).u32(0), 8u);
  EXPECT_EQ(plc.write(reg::command, {1, 800}), 0x04);
  EXPECT_EQ(plc.holding(reg::command, 1).regs[0], 0);  // the fault took the run out of force
  EXPECT_EQ(sim.control("set error_bits 0"), "ok error_bits=0");
  ASSERT_EQ(plc.write(reg::command, {0 /*stop*/}), 0);
  ASSERT_TRUE(eventually([&] { return plc.input(reg::speed, 1).regs[0] == 0; }, 10s));
}

// A description given as a path, broken: the daemon refuses the configuration with every error
// of the file, FILE:LINE: key: what, and names the option; a good one is found by its path.
TEST_F(FramedE2E, ADescriptionByPathIsCheckedWithTheConfiguration) {
  const auto file = dir_ / "acme.toml";
  std::ofstream(file) << "[protocol]\nname = \"acme\"\nsummary = \"x\"\n\n[line]\nbaud = 9601\n"
                         "parity = \"mark\"\n";
  std::ofstream(dir_ / "drivegate.toml") << config(dir_ / "tty", file.string());
  Child check({(bin_dir() / "drivegated").string(), "--check-config",
               (dir_ / "drivegate.toml").string(), "--plugin-dir", plugin_dir().string()},
              dir_ / "check.err");
  EXPECT_EQ(check.wait_exit(10s), 1);
  const std::string err = slurp(dir_ / "check.err");
  EXPECT_THAT(err, ::testing::HasSubstr(
                       "drivegate.toml:11: device[0].options (device 'washer'): option protocol: " +
                       file.string() +
                       ": message: a description needs at least "
                       "one [[message]]; "));
  EXPECT_THAT(
      err, ::testing::HasSubstr(file.string() + ":1: protocol.document: required key is missing"));
  EXPECT_THAT(
      err, ::testing::HasSubstr(file.string() + ":7: line.parity: must be one of none, even, odd"));
  // The shipped description, copied to a path: found by it, checked, valid.
  std::ofstream(dir_ / "washer.toml") << slurp(std::filesystem::path(DRIVEGATE_SOURCE_DIR) /
                                               "adapters/framed/protocols/nidec-washer.toml");
  std::ofstream(dir_ / "drivegate.toml") << config(dir_ / "tty", (dir_ / "washer.toml").string());
  Child ok({(bin_dir() / "drivegated").string(), "--check-config",
            (dir_ / "drivegate.toml").string(), "--plugin-dir", plugin_dir().string()},
           dir_ / "ok.err");
  EXPECT_EQ(ok.wait_exit(10s), 0) << slurp(dir_ / "ok.err");
}

}  // namespace
}  // namespace drivegate::test::framed_e2e_test
