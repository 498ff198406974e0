// Writes that tell the truth, on the wire: Modbus requests as raw bytes to the real daemon on a
// simulated drive of the tests' own (test-drive, tests/support/test_adapter), the exact response
// bytes, and the registers a PLC reads afterwards.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using Pdu = std::vector<std::uint8_t>;

std::string device(const std::filesystem::path& port, const std::string& options) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
         "unit_id = 1\n" +
         options;
}

class TruthfulWrites : public ::testing::Test {
 protected:
  void start(const std::string& options = "") {
    sim_ = std::make_unique<Sim>("test-drive", dir_ / "line");
    daemon_ = std::make_unique<Daemon>(dir_, device(dir_ / "line", options));
    plc_ = std::make_unique<Plc>(daemon_->port());
    ASSERT_TRUE(plc_->connect());
    ASSERT_TRUE(
        eventually([&] { return (plc_->input(reg::status, 1).regs[0] & reg::online) != 0; }, 10s))
        << "never online; sim says " << sim_->control("state");
  }
  Pdu request(const Pdu& pdu) { return raw_request(daemon_->port(), 1, pdu); }

  TempDir dir_;
  std::unique_ptr<Sim> sim_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Plc> plc_;
};

// FC 0x17 reading an unmapped address (holding 3) while writing setpoint_rpm (holding 1): the
// read range is checked first, the answer is 0x02 and the setpoint is not touched.
TEST_F(TruthfulWrites, ReadWriteWithABadReadRangeWritesNothing) {
  start();
  ASSERT_EQ(plc_->write(reg::setpoint, {600}), 0);
  // 0x17 | read 3, 1 | write 1, 1 | 2 bytes | 1200
  EXPECT_EQ(request({0x17, 0x00, 0x03, 0x00, 0x01, 0x00, 0x01, 0x00, 0x01, 0x02, 0x04, 0xB0}),
            (Pdu{0x97, 0x02}));
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 600);
  // The same with a good read range writes, then reads back what the drive holds.
  EXPECT_EQ(request({0x17, 0x00, 0x00, 0x00, 0x02, 0x00, 0x01, 0x00, 0x01, 0x02, 0x04, 0xB0}),
            (Pdu{0x17, 0x04, 0x00, 0x00, 0x04, 0xB0}));
}

// FC 0x10 writing command = run_reverse and setpoint_rpm = 1500 to a drive that turns one way
// (a compressor): 0x03, and the setpoint stays as it was.
TEST_F(TruthfulWrites, ARequestWithAPartTheDriveCannotDoChangesNothing) {
  start("[device.options]\none_way = true\n");
  ASSERT_EQ(plc_->write(reg::setpoint, {3000}), 0);
  // 0x10 | start 0 | 2 registers | 4 bytes | run_reverse, 1500
  EXPECT_EQ(request({0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x00, 0x02, 0x05, 0xDC}),
            (Pdu{0x90, 0x03}));
  const auto hr = plc_->holding(reg::command, 2);
  EXPECT_EQ(hr.regs[0], 0);                                                 // stop, still in force
  EXPECT_EQ(hr.regs[1], 3000);                                              // the setpoint it held
  EXPECT_THAT(sim_->control("state"), ::testing::HasSubstr(" target=0 "));  // never sent a run
}

// A drive that stops answering with a fault standing: fault_code says comm_lost, the stale fault
// stays visible in fault_mask and native_fault.
TEST_F(TruthfulWrites, WhileCommLostFaultCodeIsCommLost) {
  start();
  sim_->control("fault over_current");
  ASSERT_TRUE(eventually([&] { return plc_->input(reg::fault_code, 1).regs[0] == 4; }, 5s));
  sim_->control("silent on");
  ASSERT_TRUE(
      eventually([&] { return (plc_->input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 10s));
  const auto r = plc_->input(reg::status, 6);
  EXPECT_EQ(r.regs[reg::fault_code], 1);  // comm_lost
  EXPECT_EQ(r.u32(reg::fault_mask), (1u << 1) | (1u << 4));
  EXPECT_EQ(r.u32(reg::native_fault), 1u);  // test-drive's over_current
}

}  // namespace
}  // namespace drivegate::test
