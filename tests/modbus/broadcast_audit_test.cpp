// A broadcast write on a serial listener with broadcast = false (docs/serial-listeners.md) is
// applied to no drive, and the audit trail says why: the listener's broadcast setting, not an
// access level the master's session has. Through the daemon's own pieces: a SlaveHost on RTU
// frames, the Modbus backend (modbus/backend_switch.h), the gateway and its history.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "manual_clock.h"
#include "modbus/backend_switch.h"
#include "modbus/slave_host.h"
#include "one_fake_device.h"

namespace drivegate {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

TEST(BroadcastAudit, ARefusedBroadcastIsRecordedWithItsOwnReason) {
  History history;
  test::OneFakeDevice fake(&history);
  Gateway* gateway = fake.gateway();
  ASSERT_NE(gateway, nullptr);
  BackendSwitch backend;
  backend.set(gateway);

  // An operate listener on a serial line, broadcast = false (the default).
  auto policy = std::make_shared<slave::SlavePolicy>();
  policy->session.access = AccessLevel::operate;
  policy->session.source.kind = SourceKind::modbus_serial;
  policy->session.source.listener = "/dev/ttyS1";
  slave::LineCounters counters;
  test::ManualClock clock;
  std::vector<Bytes> sent;
  const auto host = std::make_shared<slave::SlaveHost>(
      fake.io(), clock, backend, modbus::DeviceIdentity{}, modbus_serial::Framing::rtu,
      modbus::Delimit::length, modbus::LineTiming{}, policy, counters, fake.log(), "/dev/ttyS1",
      [&](Bytes frame) { sent.push_back(std::move(frame)); });
  // FC 06 to address 0: setpoint_rpm (holding 1) := 1200.
  host->receive(modbus_serial::encode(modbus_serial::Framing::rtu, modbus_serial::kBroadcast,
                                      Bytes{0x06, 0x00, 0x01, 0x04, 0xB0}));
  fake.io().poll();

  EXPECT_TRUE(sent.empty());  // a broadcast is never answered
  EXPECT_EQ(counters.counts.broadcasts_refused, 1u);
  EXPECT_EQ(gateway->find("d1")->writes_in_flight(), 0u);
  const auto c = history.events().query({.kind = EventKind::command});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].device, "");
  EXPECT_EQ(c[0].unit, 0);
  EXPECT_EQ(c[0].field("source"), "modbus_serial");
  EXPECT_EQ(c[0].field("points"), "pdu 06 00 01 04 b0");
  EXPECT_EQ(c[0].field("result"), "refused");
  EXPECT_THAT(std::string(c[0].field("why")), HasSubstr("broadcast = false"));
  EXPECT_THAT(std::string(c[0].field("why")), Not(HasSubstr("access")));
  host->stop();
}

}  // namespace
}  // namespace drivegate
