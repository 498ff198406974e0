// What every adapter's descriptor must hold, checked the same way for each (the tests are in
// descriptor_contract_test.cpp, which every adapter's test binary compiles: tests/CMakeLists.txt,
// drivegate_add_adapter_test). The adapter's plugin_test.cpp states the facts of its document
// and instantiates the tests with them, in one line; a binary that does not fails
// GoogleTestVerification.UninstantiatedParameterizedTestSuite.
//
//   using test::DescriptorContract;
//   const test::DescriptorFacts kFacts{.id = "fdc1", .options = kOptionSchema, ...};
//   INSTANTIATE_TEST_SUITE_P(Fdc1, DescriptorContract, testing::Values(kFacts));
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <ostream>
#include <span>
#include <string_view>

#include "bus_rig.h"
#include "drivegate/adapter.h"

namespace drivegate::test {

struct DescriptorFacts {
  std::string_view id;
  std::span<const OptionSpec> options;  // the schema the adapter's settings parse
  LineDefaults line;                    // the document's line settings
  std::uint32_t address_min = 0;        // {0, 0}: the protocol has no address
  std::uint32_t address_max = 0;
  std::uint32_t default_address = 0;
  bool streaming = false;
  OptionText demo_options;  // exactly these, in this order
  std::int32_t demo_rpm = 0;
  std::size_t action_count = 0;  // maintenance actions (`drivegate action`)
};

inline void PrintTo(const DescriptorFacts& f, std::ostream* os) {
  *os << f.id;
}

class DescriptorContract : public testing::TestWithParam<DescriptorFacts> {};

}  // namespace drivegate::test
