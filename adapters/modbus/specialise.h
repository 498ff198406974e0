// The descriptor of one profile's devices (AdapterDescriptor::specialise): the modbus adapter's
// own, with the options the profile declares ([options.NAME], profile_options.h) after the
// adapter's, so that the core validates a device's [device.options] against them (a value out of
// range, or an option the profile does not declare, is a configuration error naming its line;
// a required option left out is refused when the device is made, naming the device's line)
// and a reload that changes one makes the device changed. Made once per profile text and kept
// for the process's lifetime.
#pragma once

#include <string>

#include "drivegate/adapter.h"

namespace drivegate::modbus_device {

// The descriptor for the profile `options` name, derived from `base` (the plugin's own). A
// profile that does not load gets `base`'s schema as it is (its errors are the driver's to tell,
// as they always were), never nullptr.
const AdapterDescriptor* specialise(const AdapterDescriptor& base, const Options& options,
                                    std::string& error);

}  // namespace drivegate::modbus_device
