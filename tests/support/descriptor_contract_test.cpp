// What every adapter's descriptor must hold (descriptor_contract.h), checked against the
// descriptor this binary's adapter exports, with the facts its plugin_test.cpp states: the API
// version and id the loader checks, the option schema it validates device options against, the
// line and address range `drivegate regmap` and the configuration check read, the demo
// `drivegate demo` runs, and the points `drivegate action` writes.
#include "descriptor_contract.h"

#include <algorithm>
#include <string>
#include <vector>

#include "adapter_bench.h"
#include "adapter_factories.h"
#include "adapter_under_test.h"
#include "plugin/adapter_options.h"

namespace drivegate::test {
namespace {

using namespace common_block;

TEST_P(DescriptorContract, SpeaksThisApiVersionUnderItsOwnId) {
  const AdapterDescriptor& a = drivegate_adapter;
  EXPECT_EQ(a.api_version, kAdapterApiVersion);
  EXPECT_EQ(std::string_view(a.id), GetParam().id);
  ASSERT_NE(a.summary, nullptr);
  EXPECT_FALSE(std::string_view(a.summary).empty());
  EXPECT_NE(a.create_driver, nullptr);
  EXPECT_NE(a.create_simulator, nullptr);
}

TEST_P(DescriptorContract, ExportsItsOptionSchemaWithDefaultsThatParse) {
  const AdapterDescriptor& a = drivegate_adapter;
  EXPECT_EQ(a.options, GetParam().options.data());
  EXPECT_EQ(a.option_count, GetParam().options.size());
  EXPECT_EQ(check_option_schema(a), "");  // every option has a default its own spec accepts
  EXPECT_NO_THROW(options_of(a));
}

TEST_P(DescriptorContract, DeclaresTheDocumentsLine) {
  const LineDefaults& line = drivegate_adapter.line;
  const LineDefaults& want = GetParam().line;
  EXPECT_EQ(line.baud, want.baud);
  EXPECT_EQ(line.parity, want.parity);
  EXPECT_EQ(line.data_bits, want.data_bits);
  EXPECT_EQ(line.stop_bits, want.stop_bits);
  EXPECT_EQ(line.echo, want.echo);
  // A streaming adapter must be alone on its line: the configuration check reads this.
  EXPECT_EQ(drivegate_adapter.streaming, GetParam().streaming);
}

// Devices and simulators are made at the default address and the highest, and refused just
// outside the range, naming the address; a protocol without addresses ({0, 0}) has no outside.
TEST_P(DescriptorContract, TheFactoriesTakeTheAddressRangeAndNothingOutsideIt) {
  const AdapterDescriptor& a = drivegate_adapter;
  const DescriptorFacts& f = GetParam();
  // An adapter whose devices follow a description they name (AdapterDescriptor::specialise)
  // makes one only with a description: its demo's.
  const OptionText options = a.specialise != nullptr ? f.demo_options : OptionText{};
  EXPECT_EQ(a.address_min, f.address_min);
  EXPECT_EQ(a.address_max, f.address_max);
  EXPECT_EQ(a.default_address, f.default_address);
  EXPECT_LE(a.address_min, a.default_address);
  EXPECT_LE(a.default_address, a.address_max);
  for (const std::uint32_t address : {a.default_address, a.address_max}) {
    SCOPED_TRACE(address);
    EXPECT_NE(make_driver(a, {.options = options, .address = address}), nullptr);
    EXPECT_NE(make_simulator(a, address, options), nullptr);
  }
  if (a.address_max == 0) return;
  std::vector<std::uint32_t> outside = {a.address_max + 1};
  if (a.address_min > 0) outside.push_back(a.address_min - 1);
  for (const std::uint32_t address : outside) {
    SCOPED_TRACE(address);
    DeviceEnv env;
    env.address = address;
    env.options = options_of(a, options);
    std::string error;
    EXPECT_EQ(a.create_driver(env, error), nullptr);
    EXPECT_NE(error.find("address"), std::string::npos) << error;
    SimEnv sim;
    sim.address = address;
    sim.options = env.options;
    error.clear();
    EXPECT_EQ(a.create_simulator(sim, error), nullptr);
    EXPECT_NE(error.find("address"), std::string::npos) << error;
  }
}

// An option the schema takes and the settings refuse makes neither a device nor a simulator, at
// the default address, and both factories say why.
TEST_P(DescriptorContract, TheFactoriesRefuseWhatTheSettingsRefuseSayingWhy) {
  const AdapterDescriptor& a = drivegate_adapter;
  for (const RefusedOption& r : GetParam().refused) {
    SCOPED_TRACE(r.name + " = " + r.value);
    DeviceEnv env;
    env.address = a.default_address;
    env.options = options_of(a, {{r.name, r.value}});
    std::string error;
    EXPECT_EQ(a.create_driver(env, error), nullptr);
    EXPECT_NE(error.find(r.error), std::string::npos) << error;
    SimEnv sim;
    sim.address = a.default_address;
    sim.options = env.options;
    error.clear();
    EXPECT_EQ(a.create_simulator(sim, error), nullptr);
    EXPECT_NE(error.find(r.error), std::string::npos) << error;
  }
}

TEST_P(DescriptorContract, TheDemoHasTheAdaptersOwnOptionsAndSpeed) {
  const DemoSetup& demo = drivegate_adapter.demo;
  const DescriptorFacts& f = GetParam();
  ASSERT_EQ(demo.option_count, f.demo_options.size());
  EXPECT_EQ(demo.options == nullptr, demo.option_count == 0);
  for (std::size_t i = 0; i < demo.option_count; ++i) {
    EXPECT_EQ(std::string_view(demo.options[i].name), f.demo_options[i].first);
    EXPECT_EQ(std::string_view(demo.options[i].value), f.demo_options[i].second);
  }
  EXPECT_EQ(demo.running_rpm, f.demo_rpm);
  EXPECT_NO_THROW(options_of(drivegate_adapter, f.demo_options));  // they parse against the schema
}

// As `drivegate demo` runs it: the device and its simulator with the demo options, and once the
// device is online, setpoint and run_forward in one request at the demo speed. The drive takes
// it, exactly: the speed is within what the adapter accepts.
TEST_P(DescriptorContract, TheDemoDeviceRunsAtTheDemoSpeed) {
  const DemoSetup& demo = drivegate_adapter.demo;
  OptionText options;
  for (std::size_t i = 0; i < demo.option_count; ++i) {
    options.emplace_back(demo.options[i].name, demo.options[i].value);
  }
  AdapterBench b(drivegate_adapter, {.options = options});
  ASSERT_TRUE(b.until_online(Millis(0), Millis(10000)));
  EXPECT_TRUE(b.run_forward_at(static_cast<std::uint16_t>(demo.running_rpm)));
  EXPECT_EQ(b.read("setpoint_rpm"), static_cast<std::uint32_t>(demo.running_rpm));
  EXPECT_EQ(b.read("command"), cmd::run_forward);
}

// `drivegate action` writes maintenance points <parameter_prefix><key>, then 1 to the commit
// point, and reads the message point after a refusal: a device made in maintenance mode has them.
TEST_P(DescriptorContract, ActionsNameTheirPointsInMaintenanceMode) {
  const AdapterDescriptor& a = drivegate_adapter;
  EXPECT_EQ(a.action_count, GetParam().action_count);
  EXPECT_EQ(a.actions == nullptr, a.action_count == 0);
  if (a.action_count == 0) return;
  const auto d = make_driver(a, {.address = a.default_address, .maintenance = true});
  ASSERT_NE(d, nullptr);
  const auto& points = d->points();
  const auto find = [&](std::string_view name) -> const PointSpec* {
    const auto it = std::find_if(points.begin(), points.end(),
                                 [&](const PointSpec& p) { return p.name == name; });
    return it == points.end() ? nullptr : &*it;
  };
  for (std::size_t i = 0; i < a.action_count; ++i) {
    const MaintenanceAction& action = a.actions[i];
    SCOPED_TRACE(action.name);
    EXPECT_FALSE(std::string_view(action.name).empty());
    EXPECT_FALSE(std::string_view(action.summary).empty());
    const PointSpec* commit = find(action.commit_point);
    ASSERT_NE(commit, nullptr);
    EXPECT_EQ(commit->table, Table::holding);
    EXPECT_EQ(commit->access(), Access::read_write);
    // It takes the 1 the tool writes (min = max = 0: no limits).
    const bool unlimited = commit->min == 0.0 && commit->max == 0.0;
    EXPECT_TRUE(unlimited || (commit->min <= 1.0 && 1.0 <= commit->max));
    const PointSpec* message = find(action.message_point);
    ASSERT_NE(message, nullptr);
    EXPECT_EQ(message->type, PointType::string);
    const std::string_view prefix = action.parameter_prefix;
    EXPECT_TRUE(std::any_of(points.begin(), points.end(), [&](const PointSpec& p) {
      return p.name.starts_with(prefix) && &p != commit && &p != message &&
             p.access() == Access::read_write;
    }));
  }
}

}  // namespace
}  // namespace drivegate::test
