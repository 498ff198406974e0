// The descriptor of one described device (AdapterDescriptor::specialise): the framed adapter's
// own, with the description's options after `protocol`, its line, addresses, streaming and demo
// speed, so that the core validates that device's [device.options] and sets up its bus exactly as
// it does a compiled adapter's. Made once per description and kept for the process's lifetime.
#pragma once

#include <memory>
#include <string>

#include "description.h"
#include "drivegate/adapter.h"

namespace drivegate::framed {

// The specialised descriptor of the description `options` names, derived from `base` (the
// plugin's own); nullptr and `error` when there is none.
const AdapterDescriptor* specialise(const AdapterDescriptor& base, const Options& options,
                                    std::string& error);

// The id a described device's descriptor carries, "framed/NAME": the capture's pseudo-header and
// the dissector tell the protocol by it.
std::string specialised_id(const AdapterDescriptor& base, const Description& d);

}  // namespace drivegate::framed
