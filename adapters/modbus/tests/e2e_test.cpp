// The modbus adapter end to end against a Modbus slave nobody here wrote: pymodbus's serial server
// (Debian's python3-pymodbus, tests/e2e/pymodbus_serial_slave.py) on one end of a pseudo-terminal
// pair made by socat, the real daemon on the other with the example-vfd profile. What a PLC reads
// is the slave's registers scaled and mapped; what it writes reaches the slave's registers, and
// only what the slave took is answered ok; a slave that is not there is comm_lost and 0x0B without
// holding up the one that is.
#include "e2e.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "e2e_adapters.h"
#include "pymodbus_slave.h"

namespace drivegate::test::modbus_e2e_test {
namespace {

// How the core's scenarios on every drive (tests/e2e: capture, status page) run this one:
// its demo profile, example-vfd, in the simulator and the device alike.
const RegisterE2eAdapter kE2eAdapter(
    {.id = "modbus",
     .device_extra = "[device.options]\nprofile = \"example-vfd\"\n",
     .sim_args = {"--set", "profile=example-vfd"},
     .rpm = 1500,
     .protocol = "MODBUS",
     .checksum_field = "drivegate_modbus.crc.status"});

using namespace std::chrono_literals;

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
  if (!have_pymodbus_tools())
    GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  // Running (status bit 2) and faulted (bit 3) with native fault 2; 1500.0 rpm; 12.5 A.
  PymodbusSlave slave(dir, {"--unit 7", "--status 12", "--speed 15000", "--fault 2"});
  Daemon daemon(dir, config(slave.port()), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(comes_online(plc)) << slurp(dir / "drivegated.log") << slurp(dir / "slave.err");

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
  EXPECT_TRUE(
      eventually([&] { return (other.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 10s));
  EXPECT_EQ(other.write(reg::command, {1, 1000}), 0x0B);
  const auto fresh = plc.input(reg::data_age, 2);
  ASSERT_TRUE(fresh.ok());
  EXPECT_LT(fresh.u32(0), 2000u) << "unit 1's data is stale while unit 2 is silent";

  // The slave dies: unit 1 goes comm_lost too, and a write is 0x0B.
  slave.kill();
  EXPECT_TRUE(
      eventually([&] { return (plc.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 10s));
  EXPECT_EQ(plc.write(reg::command, {1, 1000}), 0x0B);
  EXPECT_EQ(daemon.stop(), 0);
}

TEST(ModbusProfileE2E, AnExceptionFromTheSlaveIs0x04AtThePlc) {
  if (!have_pymodbus_tools())
    GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  // The slave has no holding 0, the profile's control word: it answers every write there with
  // exception 02, and reads of it too (the block holding it is searched: holding 0 is skipped,
  // and the rest of the device read around it).
  PymodbusSlave slave(dir, {"--unit 7", "--no-control", "--speed 300"});
  Daemon daemon(dir, config(slave.port()), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(comes_online(plc)) << slurp(dir / "drivegated.log");
  EXPECT_TRUE(eventually(
      [&] { return static_cast<std::int16_t>(plc.input(reg::speed, 1).regs[0]) == 30; }, 5s));
  EXPECT_EQ(plc.write(reg::command, {1}), 4);
  EXPECT_EQ(plc.holding(reg::command, 1).regs[0], 0);  // still stop: the run was not taken
  EXPECT_EQ(slave.writes().find("write holding 0"), std::string::npos);
}

// Pass-through: unit 3 is a window onto the slave at 7, unit 4 onto 9 where nobody answers;
// a second listener may only read.
std::string passthrough_config(const std::filesystem::path& port, int read_port) {
  return maintain_and_read_listeners(read_port) + "[[bus]]\nname = \"line-a\"\nport = \"" +
         port.string() +
         "\"\nbaud = 19200\nparity = \"even\"\n\n"
         "[[device]]\nname = \"window\"\nbus = \"line-a\"\nadapter = \"modbus\"\nunit_id = 3\n"
         "address = 7\n[device.options]\npassthrough = true\n\n"
         "[[device]]\nname = \"nobody\"\nbus = \"line-a\"\nadapter = \"modbus\"\nunit_id = 4\n"
         "address = 9\n[device.options]\npassthrough = true\ncomm_timeout_ms = 1500\n";
}

using Pdu = std::vector<std::uint8_t>;

TEST(ModbusPassthroughE2E, EveryFunctionIsTheSlavesOwnAnswerAndReadListenersOnlyRead) {
  if (!have_pymodbus_tools())
    GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  // Holding 0 = 0x0006, 1 = 0, 100 = 12; its identification as a vendor's would be.
  PymodbusSlave slave(
      dir, {"--unit 7", "--status 12", "--vendor Acme", "--product-code VF-9", "--revision 2.1"});
  const int read_port = free_port();
  Daemon daemon(dir, passthrough_config(slave.port(), read_port), {}, dir / "drivegated.log");
  const int rw = daemon.port();  // --listen: the first listener's address, access maintain

  // FC 03 (Application Protocol 6.3): holding 0..1 as the slave holds them.
  ASSERT_TRUE(eventually(
      [&] {
        return raw_request(rw, 3, {0x03, 0x00, 0x00, 0x00, 0x02}) ==
               Pdu{0x03, 0x04, 0x00, 0x06, 0x00, 0x00};
      },
      10s))
      << slurp(dir / "drivegated.log") << slurp(dir / "slave.err");
  // FC 06 (6.6): the echo, and the write reached the slave.
  EXPECT_EQ(raw_request(rw, 3, {0x06, 0x00, 0x01, 0x04, 0xD2}),
            (Pdu{0x06, 0x00, 0x01, 0x04, 0xD2}));
  EXPECT_NE(slave.writes().find("write holding 1 1234\n"), std::string::npos) << slave.writes();
  // FC 16 (6.12): address and quantity.
  EXPECT_EQ(raw_request(rw, 3, {0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x00, 0x0F, 0x05, 0xDC}),
            (Pdu{0x10, 0x00, 0x00, 0x00, 0x02}));
  EXPECT_NE(slave.writes().find("write holding 0 15 1500\n"), std::string::npos) << slave.writes();
  // FC 17 (6.17): write holding 1 := 900, then read holding 100 (12).
  EXPECT_EQ(
      raw_request(rw, 3, {0x17, 0x00, 0x64, 0x00, 0x01, 0x00, 0x01, 0x00, 0x01, 0x02, 0x03, 0x84}),
      (Pdu{0x17, 0x02, 0x00, 0x0C}));
  EXPECT_NE(slave.writes().find("write holding 1 900\n"), std::string::npos) << slave.writes();
  // FC 2B / 0E (6.21), basic identification: the slave's objects, not the gateway's.
  const Pdu id = raw_request(rw, 3, {0x2B, 0x0E, 0x01, 0x00});
  ASSERT_GE(id.size(), 8u);
  EXPECT_EQ(Pdu(id.begin(), id.begin() + 3), (Pdu{0x2B, 0x0E, 0x01}));
  const std::string objects(id.begin(), id.end());
  EXPECT_NE(objects.find("Acme"), std::string::npos);
  EXPECT_NE(objects.find("VF-9"), std::string::npos);
  EXPECT_EQ(objects.find("drivegate"), std::string::npos);
  // A register the slave lacks: its exception 02, as it came.
  EXPECT_EQ(raw_request(rw, 3, {0x03, 0x13, 0x88, 0x00, 0x01}), (Pdu{0x83, 0x02}));

  // The read listener forwards reads, and refuses every write with 01 before the line.
  const std::string before = slave.writes();
  EXPECT_EQ(raw_request(read_port, 3, {0x03, 0x00, 0x01, 0x00, 0x01}),
            (Pdu{0x03, 0x02, 0x03, 0x84}));
  EXPECT_EQ(raw_request(read_port, 3, {0x06, 0x00, 0x01, 0x00, 0x07}), (Pdu{0x86, 0x01}));
  EXPECT_EQ(raw_request(read_port, 3,
                        {0x17, 0x00, 0x64, 0x00, 0x01, 0x00, 0x01, 0x00, 0x01, 0x02, 0x00, 0x07}),
            (Pdu{0x97, 0x01}));
  EXPECT_EQ(slave.writes(), before);

  // Nobody at 9: 0x0B, and the window at 7 answers all along.
  EXPECT_EQ(raw_request(rw, 4, {0x03, 0x00, 0x00, 0x00, 0x01}), (Pdu{0x83, 0x0B}));
  EXPECT_EQ(raw_request(rw, 3, {0x03, 0x00, 0x64, 0x00, 0x01}), (Pdu{0x03, 0x02, 0x00, 0x0C}));
  EXPECT_EQ(daemon.stop(), 0);
}

}  // namespace
}  // namespace drivegate::test::modbus_e2e_test
