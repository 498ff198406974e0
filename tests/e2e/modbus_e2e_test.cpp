// The modbus adapter end to end against a Modbus slave nobody here wrote: pymodbus's serial server
// (Debian's python3-pymodbus, tests/e2e/pymodbus_serial_slave.py) on one end of a pseudo-terminal
// pair made by socat, the real daemon on the other with the example-vfd profile. What a PLC reads
// is the slave's registers scaled and mapped; what it writes reaches the slave's registers, and
// only what the slave took is answered ok; a slave that is not there is comm_lost and 0x0B without
// holding up the one that is.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

std::filesystem::path slave_script() {
  return std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "tests/e2e/pymodbus_serial_slave.py";
}

bool have_tools() {
  return std::filesystem::exists("/usr/bin/socat") && std::filesystem::exists(kSystemPython) &&
         std::filesystem::exists("/usr/lib/python3/dist-packages/pymodbus");
}

// socat's two linked pseudo-terminals, `a` (the daemon's) and `b` (the slave's), and the slave.
class PymodbusSlave {
 public:
  PymodbusSlave(const TempDir& dir, std::vector<std::string> args)
      : a_(dir / "a"),
        out_(dir / "slave.out"),
        socat_({"/usr/bin/socat", "pty,raw,echo=0,link=" + (dir / "a").string(),
                "pty,raw,echo=0,link=" + (dir / "b").string()},
               dir / "socat.err") {
    for (int i = 0; i < 100 && !std::filesystem::exists(dir / "b"); ++i) {
      std::this_thread::sleep_for(20ms);
    }
    std::vector<std::string> argv = {"/bin/sh", "-c",
                                     "exec " + kSystemPython + " " + slave_script().string() +
                                         " --port " + (dir / "b").string()};
    for (const auto& x : args) argv[2] += " " + x;
    argv[2] += " > " + out_.string();
    slave_ = std::make_unique<Child>(argv, dir / "slave.err");
    for (int i = 0; i < 200 && slurp(out_).find("ready") == std::string::npos; ++i) {
      std::this_thread::sleep_for(20ms);
    }
  }
  [[nodiscard]] const std::filesystem::path& port() const { return a_; }
  // What reached the slave: its `write TABLE ADDRESS VALUE...` lines.
  [[nodiscard]] std::string writes() const { return slurp(out_); }
  void kill() { slave_.reset(); }

 private:
  std::filesystem::path a_;
  std::filesystem::path out_;
  Child socat_;
  std::unique_ptr<Child> slave_;
};

// Unit 1: the slave at address 7; unit 2: address 8, where nobody answers.
std::string config(const std::filesystem::path& port) {
  return "[[bus]]\nname = \"line-a\"\nport = \"" + port.string() +
         "\"\nbaud = 19200\nparity = \"even\"\n\n"
         "[[device]]\nname = \"fan-3\"\nbus = \"line-a\"\nadapter = \"modbus\"\nunit_id = 1\n"
         "address = 7\npoll_ms = 200\n[device.options]\nprofile = \"example-vfd\"\n\n"
         "[[device]]\nname = \"fan-4\"\nbus = \"line-a\"\nadapter = \"modbus\"\nunit_id = 2\n"
         "address = 8\npoll_ms = 200\n[device.options]\nprofile = \"example-vfd\"\n"
         "comm_timeout_ms = 1500\n";
}

// motor_current, the profile's one point of its own: after the 32-register common input block.
constexpr int kMotorCurrent = 32;

float f32_of(const Plc::Read& r) {
  const std::uint32_t bits = r.u32(0);  // the listener's default word order: high word first
  float f = 0;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

TEST(ModbusProfileE2E, APlcReadsThePymodbusSlavesRegistersAndItsWritesReachThem) {
  if (!have_tools()) GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  // Running (status bit 2) and faulted (bit 3) with native fault 2; 1500.0 rpm; 12.5 A.
  PymodbusSlave slave(dir, {"--unit 7", "--status 12", "--speed 15000", "--fault 2"});
  Daemon daemon(dir, config(slave.port()), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return (plc.input(reg::status, 1).regs[0] & reg::online) != 0; },
                         10s))
      << slurp(dir / "drivegated.log") << slurp(dir / "slave.err");

  // The map: speed 15000 x 0.1; the run and fault bits; native 2 = over_current (4) by the map.
  const auto block = plc.input(0, 8);
  ASSERT_TRUE(block.ok());
  EXPECT_EQ(static_cast<std::int16_t>(block.regs[reg::speed]), 1500);
  EXPECT_NE(block.regs[reg::status] & reg::running, 0);
  EXPECT_NE(block.regs[reg::status] & reg::fault, 0);
  EXPECT_EQ(block.regs[reg::fault_code], 4);  // over_current
  EXPECT_EQ(block.u32(reg::native_fault), 2u);
  EXPECT_FLOAT_EQ(f32_of(plc.input(kMotorCurrent, 2)), 12.5f);

  // reset_fault, then setpoint and run in one request, then stop: each reaches the slave's
  // control word (holding 0) and reference (holding 1), and is answered once the slave took it.
  EXPECT_EQ(plc.write(reg::command, {4}), 0);
  EXPECT_NE(slave.writes().find("write holding 0 128\n"), std::string::npos) << slave.writes();
  EXPECT_EQ(plc.write(reg::command, {1, 1200}), 0);
  const std::string w = slave.writes();
  EXPECT_NE(w.find("write holding 1 1200\nwrite holding 0 15\n"), std::string::npos) << w;
  EXPECT_EQ(plc.holding(reg::setpoint, 1).regs[0], 1200);
  EXPECT_EQ(plc.write(reg::command, {0}), 0);
  EXPECT_NE(slave.writes().find("write holding 0 6\n"), std::string::npos);
  // Beyond the reference's max (3000): refused before anything is sent.
  const auto before = slave.writes();
  EXPECT_EQ(plc.write(reg::setpoint, {3001}), 3);
  EXPECT_EQ(slave.writes(), before);

  // Unit 2's slave is not there: comm_lost, writes 0x0B, and unit 1 is polled all along.
  Plc other(daemon.port(), 2);
  ASSERT_TRUE(other.connect());
  EXPECT_TRUE(eventually(
      [&] { return (other.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 10s));
  EXPECT_EQ(other.write(reg::command, {1, 1000}), 0x0B);
  const auto fresh = plc.input(reg::data_age, 2);
  ASSERT_TRUE(fresh.ok());
  EXPECT_LT(fresh.u32(0), 2000u) << "unit 1's data is stale while unit 2 is silent";

  // The slave dies: unit 1 goes comm_lost too, and a write is 0x0B.
  slave.kill();
  EXPECT_TRUE(eventually(
      [&] { return (plc.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 10s));
  EXPECT_EQ(plc.write(reg::command, {1, 1000}), 0x0B);
  EXPECT_EQ(daemon.stop(), 0);
}

TEST(ModbusProfileE2E, AnExceptionFromTheSlaveIs0x04AtThePlc) {
  if (!have_tools()) GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  // The slave has no holding 0, the profile's control word: it answers every write there with
  // exception 02, and reads of it too (the rest of the device is read point by point).
  PymodbusSlave slave(dir, {"--unit 7", "--no-control", "--speed 300"});
  Daemon daemon(dir, config(slave.port()), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return (plc.input(reg::status, 1).regs[0] & reg::online) != 0; },
                         10s))
      << slurp(dir / "drivegated.log");
  EXPECT_TRUE(eventually(
      [&] { return static_cast<std::int16_t>(plc.input(reg::speed, 1).regs[0]) == 30; }, 5s));
  EXPECT_EQ(plc.write(reg::command, {1}), 4);
  EXPECT_EQ(plc.holding(reg::command, 1).regs[0], 0);  // still stop: the run was not taken
  EXPECT_EQ(slave.writes().find("write holding 0"), std::string::npos);
}

}  // namespace
}  // namespace drivegate::test
