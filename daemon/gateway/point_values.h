// Every point of a device with its value, as a client in the map's word order would read it, all
// as of one moment: what the status documents and the MQTT northbound publish. Each table is read
// in as few Device::read calls as it has mapped runs, so the common block's inputs and status
// bits are computed once per table, not once per point.
#pragma once

#include <string_view>
#include <utility>
#include <vector>

#include "drivegate/driver.h"
#include "drivegate/point.h"
#include "gateway/device.h"

namespace drivegate {

using PointValue = std::pair<const MappedPoint*, Value>;

// The name of `value` in the point's labels, or "" (a value without a name, or a bit field).
std::string_view label_of(const PointSpec& spec, const Value& value);

// The common block, then the adapter's points, in the map's order; a point that cannot be read
// is left out, one whose value is not known is std::monostate (an adapter's point its driver does
// not know, a common row holding its unknown mark, a float that is not a number); a string point's
// value is its registers' text (decode_text). `out` is
// replaced (its capacity kept, for the next device).
void point_values(Device& device, TimePoint now, std::vector<PointValue>& out);

// The same at Clock::now(), in a new vector.
std::vector<PointValue> point_values(Device& device);

}  // namespace drivegate
