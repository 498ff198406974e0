// What every adapter's descriptor must hold, checked the same way for each (the tests are in
// descriptor_contract_test.cpp, which every adapter's test binary compiles: tests/CMakeLists.txt,
// drivegate_add_adapter_test). The adapter's plugin_test.cpp states the facts of its document
// and instantiates the tests with them, in one line; a binary that does not fails
// GoogleTestVerification.UninstantiatedParameterizedTestSuite.
//
//   using test::DescriptorContract;
//   const test::DescriptorFacts kFacts{.id = "fdc1", .options = kOptionSchema, ...};
//   INSTANTIATE_TEST_SUITE_P(Fdc1, DescriptorContract, testing::Values(kFacts));
//
// Beside it, what each adapter's tests of its options ask in the same words: the settings its
// parse_settings makes of options over the schema's defaults, and the values refused.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <ostream>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "bus_rig.h"
#include "drivegate/adapter.h"

namespace drivegate::test {

// An option value the schema takes and the adapter's settings refuse, and what the refusal says.
struct RefusedOption {
  std::string name;
  std::string value;
  std::string error;  // found in the error of both factories
};

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
  std::size_t action_count = 0;        // maintenance actions (`drivegate action`)
  std::vector<RefusedOption> refused;  // neither factory makes anything of each
};

inline void PrintTo(const DescriptorFacts& f, std::ostream* os) {
  *os << f.id;
}

class DescriptorContract : public testing::TestWithParam<DescriptorFacts> {};

// The settings `parse` makes of `set` over the adapter's schema defaults; a test failure, and
// default settings, if it refuses them.
template <class Settings>
Settings settings_of(const AdapterDescriptor& adapter,
                     std::optional<Settings> (*parse)(const Options&, std::string&),
                     const OptionText& set = {}) {
  std::string error;
  std::optional<Settings> settings = parse(options_of(adapter, set), error);
  EXPECT_TRUE(settings.has_value()) << error;
  return settings.value_or(Settings{});
}

// Each of `values`, alone, is kept out by the adapter's schema (what no frame can carry).
inline void expect_schema_refuses(const AdapterDescriptor& adapter, const OptionText& values) {
  for (const auto& value : values) {
    EXPECT_THROW(options_of(adapter, {value}), std::invalid_argument)
        << value.first << " = " << value.second;
  }
}

// Each of `values`, alone, passes the schema and is refused by `parse` with an error that names
// the option.
template <class Settings>
void expect_settings_refuse(const AdapterDescriptor& adapter,
                            std::optional<Settings> (*parse)(const Options&, std::string&),
                            const OptionText& values) {
  for (const auto& value : values) {
    std::string error;
    EXPECT_FALSE(parse(options_of(adapter, {value}), error))
        << value.first << " = " << value.second;
    EXPECT_NE(error.find(value.first), std::string::npos) << error;
  }
}

}  // namespace drivegate::test
