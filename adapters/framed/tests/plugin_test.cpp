// The framed plugin: its descriptor's contract (tests/support/descriptor_contract.h), and the
// descriptor it specialises for a described device.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "adapter_under_test.h"
#include "descriptor_contract.h"
#include "settings.h"

namespace drivegate::framed {
namespace {

using ::drivegate::test::DescriptorContract;
using ::testing::HasSubstr;

// Its own schema is `protocol`; the line and addresses are the description's (below). The demo
// runs the described washer at 800 rpm.
const ::drivegate::test::DescriptorFacts kFacts{.id = "framed",
                                   .options = kOptionSchema,
                                   .line = {9600, Parity::none, 8, 1, false},
                                   .demo_options = {{"protocol", "nidec-washer"}},
                                   .demo_rpm = 800};
INSTANTIATE_TEST_SUITE_P(Framed, DescriptorContract, testing::Values(kFacts));

Options with_protocol(const std::string& p) {
  Options o;
  o.set("protocol", p);
  return o;
}

TEST(FramedPlugin, SpecialisesADeviceToItsDescription) {
  std::string error;
  const AdapterDescriptor* a = drivegate_adapter.specialise(with_protocol("nidec-washer"), error);
  ASSERT_NE(a, nullptr) << error;
  EXPECT_STREQ(a->id, "framed/nidec-washer");
  EXPECT_EQ(a->line.baud, 4800u);
  EXPECT_EQ(a->line.parity, Parity::odd);
  EXPECT_TRUE(a->line.echo);
  EXPECT_EQ(a->address_max, 0u);
  EXPECT_FALSE(a->streaming);
  EXPECT_EQ(a->create_driver, drivegate_adapter.create_driver);
  ASSERT_EQ(a->option_count, 5u);  // protocol, then the description's own
  EXPECT_STREQ(a->options[0].name, "protocol");
  EXPECT_STREQ(a->options[1].name, "platform");
  EXPECT_STREQ(a->options[1].default_value, "7");
  EXPECT_EQ(a->specialise, nullptr);
  ASSERT_EQ(a->demo.option_count, 1u);  // the demo of this description, at its speed
  EXPECT_STREQ(a->demo.options[0].value, "nidec-washer");
  EXPECT_EQ(a->demo.running_rpm, 800);
  // The same description: the same descriptor.
  EXPECT_EQ(drivegate_adapter.specialise(with_protocol("nidec-washer"), error), a);
}

TEST(FramedPlugin, ADescriptionThatIsNotThereIsNamed) {
  std::string error;
  EXPECT_EQ(drivegate_adapter.specialise(with_protocol("no-such-drive"), error), nullptr);
  EXPECT_THAT(error, HasSubstr("option protocol: no description 'no-such-drive' in "
                               "/etc/drivegate/protocols or /usr/share/drivegate/protocols"));
  EXPECT_EQ(drivegate_adapter.specialise(with_protocol(""), error), nullptr);
  EXPECT_THAT(error, HasSubstr("option protocol: required"));
  EXPECT_EQ(drivegate_adapter.specialise(with_protocol("/nonexistent/x.toml"), error), nullptr);
  EXPECT_THAT(error, HasSubstr("/nonexistent/x.toml is not a regular file"));
  EXPECT_EQ(drivegate_adapter.specialise(with_protocol("Bad Name"), error), nullptr);
  EXPECT_THAT(error, HasSubstr("neither a description's name"));
}

}  // namespace
}  // namespace drivegate::framed
