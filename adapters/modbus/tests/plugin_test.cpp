// The descriptor the plugin exports, with the facts every adapter states
// (tests/support/descriptor_contract.h), and its factories' own rules.
#include <gtest/gtest.h>

#include <string>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "descriptor_contract.h"
#include "gateway/gateway.h"
#include "settings.h"

namespace drivegate::modbus_device {
namespace {

using test::DescriptorContract;

// Serial Line 2.5.1: 19200 8E1 the default; 2.2: slaves 1..247. A slave only answers.
// `drivegate demo`: the example VFD at 1500 rpm; no maintenance actions.
const test::DescriptorFacts kFacts{
    .id = "modbus",
    .options = kOptionSchema,
    .line = {19200, Parity::even, 8, 1, false},
    .address_min = 1,
    .address_max = 247,
    .default_address = 1,
    .streaming = false,
    .demo_options = {{"profile", "example-vfd"}},
    .demo_rpm = 1500,
    .refused = {{"profile", "no-such-drive", "option profile: no profile 'no-such-drive'"}}};
INSTANTIATE_TEST_SUITE_P(Modbus, DescriptorContract, testing::Values(kFacts));

TEST(ModbusPlugin, TheBroadcastAddressIsNeverPolled) {
  DeviceEnv env;
  env.address = 0;
  env.options = test::options_of(drivegate_adapter);
  std::string error;
  EXPECT_FALSE(drivegate_adapter.create_driver(env, error));
  EXPECT_NE(error.find("address 0"), std::string::npos) << error;
}

// "The bus's own settings must agree" with the profile's [line]. A device on a bus
// that runs another line is refused when the configuration is loaded, naming both, rather than
// polled into silence; the daemon's own factory call (gateway.h make_driver) passes the bus.
TEST(ModbusPlugin, ABusThatDoesNotRunTheProfilesLineIsRefusedNamingBoth) {
  DeviceConfig config;
  config.name = "mmx";
  config.address = 13;
  config.options = test::options_of(drivegate_adapter, {{"profile", "eaton-m-max"}});
  config.options.set("motor_poles", 4.0);  // the profile requires it
  BusConfig bus;
  bus.baud = 19200;  // the profile says 9600 8N2 (its manual's factory setting)
  bus.parity = Parity::even;
  std::string error;
  EXPECT_EQ(make_driver(config, drivegate_adapter, false, error, &bus), nullptr);
  EXPECT_NE(error.find("says [line] 9600 baud, 8 data bits, none parity, 2 stop bits"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("the bus runs 19200 baud, 8 data bits, even parity, 1 stop bit"),
            std::string::npos)
      << error;
  bus.baud = 9600;
  bus.parity = Parity::none;
  bus.stop_bits = 2;
  EXPECT_NE(make_driver(config, drivegate_adapter, false, error, &bus), nullptr) << error;
  bus.data_bits = 7;  // RTU carries 8 (Serial Line 2.5.1)
  EXPECT_EQ(make_driver(config, drivegate_adapter, false, error, &bus), nullptr);
  // No line (printing the register map): nothing to compare.
  EXPECT_NE(make_driver(config, drivegate_adapter, false, error, nullptr), nullptr) << error;
  // A pass-through device names no profile, so no [line] to hold the bus to.
  config.options = test::options_of(drivegate_adapter, {{"passthrough", "true"}});
  EXPECT_NE(make_driver(config, drivegate_adapter, false, error, &bus), nullptr) << error;
}

}  // namespace
}  // namespace drivegate::modbus_device
