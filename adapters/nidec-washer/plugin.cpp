// The plugin descriptor: options, line defaults and the two factories.
#include <iterator>

#include "drivegate/adapter.h"
#include "driver.h"
#include "simulator.h"

namespace {

using drivegate::OptionSpec;
using drivegate::OptionType;

const OptionSpec kOptions[] = {
    {"platform", OptionType::integer, "7",
     "washer platform sent in the ping (5.1), e.g. 7 for a 7 kg washer", 0, 255},
    {"empty_raw_weight", OptionType::integer, "0",
     "empty-basket raw weight sent in the ping (5.1); 0 = no adjustment", 0, 65535},
    {"accel_time_ms", OptionType::integer, "3000",
     "initial accel time of CW/CCW/spin/free-shaft spin (sent in 100 ms units, 5.3)", 0, 6553500},
    {"attempts", OptionType::integer, "3",
     "identical sends per bus turn before giving the line to others (section 6: resend)", 1, 20},
};

std::unique_ptr<drivegate::Driver> create_driver(const drivegate::DeviceEnv& env, std::string&) {
  return std::make_unique<drivegate::nidec::WasherDriver>(drivegate::nidec::config_from(env));
}

std::unique_ptr<drivegate::Simulator> create_simulator(const drivegate::SimEnv& env, std::string&) {
  return std::make_unique<drivegate::nidec::WasherSimulator>(env);
}

}  // namespace

extern "C" DRIVEGATE_EXPORT const drivegate::AdapterDescriptor drivegate_adapter = {
    drivegate::kAdapterApiVersion,
    "nidec-washer",
    "Nidec washing-machine inverter, Elaraby bus protocol spec V07",
    kOptions,
    std::size(kOptions),
    // Section 3: 4800 baud, 8 data bits, odd parity, one stop bit; one wire, half duplex.
    {4800, drivegate::Parity::odd, 8, 1, true},
    0,  // section 2: one inverter per wire, no address in the frame
    0,
    0,
    false,  // section 2: the inverter only answers
    create_driver,
    create_simulator,
};
