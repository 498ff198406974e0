// The ed3100 option schema and factories, shared by plugin.cpp and the tests.
#pragma once

#include <array>
#include <memory>
#include <string>

#include "drivegate/adapter.h"

namespace drivegate::ed3100 {

extern const std::array<OptionSpec, 11> kOptionSpecs;

std::unique_ptr<Driver> create_driver(const DeviceEnv& env, std::string& error);
std::unique_ptr<Simulator> create_simulator(const SimEnv& env, std::string& error);

}  // namespace drivegate::ed3100
