// The descriptor the plugin exports, with the facts of the document every adapter states
// (tests/support/descriptor_contract.h): the address range too, and a motor the settings refuse.
#include <gtest/gtest.h>

#include "adapter_under_test.h"
#include "descriptor_contract.h"
#include "settings.h"

namespace drivegate::ed3100 {
namespace {

using test::DescriptorContract;

// The document offers 8N2, 8E1 and 8O1: 9600 8E1 is drivegate's default. Address 1..31 a drive,
// 0 the broadcast, 01 the factory setting. The drive only ever answers. `drivegate demo`: default
// options, 1500 rpm; no maintenance actions. rpm = Hz x 120 / poles: an odd pole count is no motor.
const test::DescriptorFacts kFacts{.id = "ed3100",
                                   .options = kOptionSchema,
                                   .line = {9600, Parity::even, 8, 1, false},
                                   .address_min = 0,
                                   .address_max = 31,
                                   .default_address = 1,
                                   .demo_rpm = 1500,
                                   .refused = {{"poles", "5", "poles: must be an even number"}}};
INSTANTIATE_TEST_SUITE_P(Ed3100, DescriptorContract, testing::Values(kFacts));

}  // namespace
}  // namespace drivegate::ed3100
