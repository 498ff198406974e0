// The descriptor of the adapter a test binary is about: each adapter's test binary compiles that
// adapter's plugin.cpp, so the tests build devices and simulators with the very factories and
// options the daemon gets from the plugin (tests/CMakeLists.txt, drivegate_add_adapter_test).
#pragma once

#include "drivegate/adapter.h"

extern "C" const drivegate::AdapterDescriptor drivegate_adapter;
