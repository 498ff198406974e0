// Plugins for the loader's tests (see plugin_test.cpp), one per build of this file: those it must
// refuse (another API version, no descriptor, an option default outside its own range) and a
// good one, which must still load beside a refused one.
#include "drivegate/adapter.h"

#if defined(BAD_API_VERSION)
extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
    .api_version = 999,
    .id = "from-the-future",
    .summary = "an adapter built for another drivegate",
    .options = nullptr,
    .option_count = 0,
    .line = {9600, drivegate::Parity::none, 8, 1, false},
    .address_min = 0,
    .address_max = 0,
    .default_address = 0,
    .streaming = false,
    .create_driver = nullptr,
    .create_simulator = nullptr,
    .demo = {}};
#elif defined(BAD_OPTION_DEFAULT) || defined(GOOD_PLUGIN)
namespace {

std::unique_ptr<drivegate::Driver> no_driver(const drivegate::DeviceEnv&, std::string& error) {
  error = "a test plugin makes no devices";
  return nullptr;
}
std::unique_ptr<drivegate::Simulator> no_simulator(const drivegate::SimEnv&, std::string& error) {
  error = "a test plugin makes no simulators";
  return nullptr;
}

#ifdef BAD_OPTION_DEFAULT
constexpr const char* kId = "bad-default";
constexpr const char* kTimeoutDefault = "5";  // below its own minimum
#else
constexpr const char* kId = "test-good";
constexpr const char* kTimeoutDefault = "100";
#endif
const drivegate::OptionSpec kOptions[] = {
    {"mode", drivegate::OptionType::string, "normal", "a choice", 0, 0, "normal|fast"},
    {"timeout_ms", drivegate::OptionType::integer, kTimeoutDefault, "reply timeout, ms", 10, 1000},
};

}  // namespace

extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
    .api_version = drivegate::kAdapterApiVersion,
    .id = kId,
    .summary = "an adapter for the loader's tests",
    .options = kOptions,
    .option_count = std::size(kOptions),
    .line = {9600, drivegate::Parity::none, 8, 1, false},
    .address_min = 0,
    .address_max = 0,
    .default_address = 0,
    .streaming = false,
    .create_driver = no_driver,
    .create_simulator = no_simulator,
    .demo = {}};
#else
extern "C" DRIVEGATE_EXPORT const int not_a_drivegate_adapter;
const int not_a_drivegate_adapter = 1;
#endif
