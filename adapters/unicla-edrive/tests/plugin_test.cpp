// The descriptor the plugin exports, with the facts of the document every adapter states
// (tests/support/descriptor_contract.h), its own address rules, and the options into settings.
#include <gtest/gtest.h>

#include <string_view>

#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "descriptor_contract.h"
#include "driver.h"
#include "settings.h"

namespace drivegate::unicla {
namespace {

using namespace std::chrono_literals;

using test::DescriptorContract;

// "Communications Settings": 19200 (the default), 8 data bits, no parity, 1 stop bit. "Device
// Address": 0x00 the master, 0xFF everyone; "Device ID ... Default Value 0x01". "All transfers are
// required to be master initiated". `drivegate demo`: default options, running at 3000 rpm; no
// maintenance actions.
const test::DescriptorFacts kFacts{.id = "unicla-edrive",
                                   .options = kOptionSchema,
                                   .line = {19200, Parity::none, 8, 1, false},
                                   .address_min = 1,
                                   .address_max = 254,
                                   .default_address = 1,
                                   .demo_rpm = 3000};
INSTANTIATE_TEST_SUITE_P(Unicla, DescriptorContract, testing::Values(kFacts));

TEST(UniclaSettings, FromTheOptions) {
  const Settings defaults = test::settings_of(drivegate_adapter, parse_settings);
  EXPECT_EQ(defaults.byte_order, ByteOrder::big);
  EXPECT_EQ(defaults.attempts, 3);
  EXPECT_EQ(defaults.reply_timeout, 100ms);
  EXPECT_EQ(defaults.confirm_timeout, 2000ms);
  // The schema's defaults are the ones Settings states.
  EXPECT_EQ(defaults.reply_timeout, Settings{}.reply_timeout);
  EXPECT_EQ(defaults.confirm_timeout, Settings{}.confirm_timeout);
  EXPECT_EQ(defaults.attempts, Settings{}.attempts);

  const Settings set = test::settings_of(drivegate_adapter, parse_settings,
                                         {{"byte_order", "little"},
                                          {"retries", "0"},
                                          {"reply_timeout_ms", "250"},
                                          {"confirm_timeout_ms", "1000"}});
  EXPECT_EQ(set.byte_order, ByteOrder::little);
  EXPECT_EQ(set.attempts, 1);
  EXPECT_EQ(set.reply_timeout, 250ms);
  EXPECT_EQ(set.confirm_timeout, 1000ms);
  // The schema keeps out what the protocol cannot do.
  test::expect_schema_refuses(
      drivegate_adapter,
      {{"byte_order", "middle"}, {"retries", "6"}, {"confirm_timeout_ms", "100"}});
}

TEST(UniclaSettings, TraitsFollowTheOptions) {
  const auto d = test::make_driver(
      drivegate_adapter,
      {.options = {{"confirm_timeout_ms", "1500"}}, .address = 1, .poll = 1000ms});
  ASSERT_NE(d, nullptr);
  const DriverTraits t = d->traits();
  // The gateway's write deadline comes after the driver's own verdict.
  EXPECT_EQ(t.write_timeout, 2500ms);
  // 4 polls + 3 attempts x (100 ms and the engine's guard time after it).
  EXPECT_EQ(t.comm_timeout, 4600ms);
  EXPECT_EQ(t.inter_frame_gap, kInterFrameGap);
}

}  // namespace
}  // namespace drivegate::unicla
