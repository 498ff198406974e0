#include "adapter_factories.h"

#include <gtest/gtest.h>

#include <string>

namespace drivegate::test {

std::unique_ptr<Driver> make_driver(const AdapterDescriptor& adapter, const DriverSetup& setup) {
  DeviceEnv env;
  env.name = "drive";
  env.address = setup.address;
  env.poll_interval = setup.poll;
  env.options = options_of(adapter, setup.options);
  env.maintenance = setup.maintenance;
  std::string error;
  auto driver = adapter.create_driver(env, error);
  if (!driver) ADD_FAILURE() << "the adapter refused the driver: " << error;
  return driver;
}

std::unique_ptr<Simulator> make_simulator(const AdapterDescriptor& adapter, std::uint32_t address,
                                          const OptionText& options) {
  SimEnv env;
  env.address = address;
  env.options = options_of(adapter, options);
  std::string error;
  auto sim = adapter.create_simulator(env, error);
  if (!sim) ADD_FAILURE() << "the adapter refused the simulator: " << error;
  return sim;
}

}  // namespace drivegate::test
