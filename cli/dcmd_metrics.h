// What `drivegate dcmd` sends and how it reads the answer, pure: METRIC=VALUE arguments as the
// metrics of a Sparkplug B DCMD (mqtt/sparkplug.h), and a DDATA of the device as the result of
// that command (docs/mqtt.md, "Commands": Command/Last Point and Command/Last Result).
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "drivegate/point.h"
#include "mqtt/sparkplug.h"
#include "point_writes.h"  // Assignment

namespace drivegate::cli {

// The metric `a` names, with its value: true or false a Boolean, a whole number an Int64, any
// other finite number a Double, else one of `point`'s labels (command=run_forward) as the Int64
// it stands for. `point` may be null (a name the map does not have: the edge node says so).
// nullopt and `error` when the value is none of these.
std::optional<sparkplug::Metric> command_metric(const Assignment& a, const PointSpec* point,
                                                std::string& error);

// `ddata`'s Command/Last Result when it reports the command that wrote `points` (the metric
// names, comma-separated, in the order sent: its Command/Last Point); nullopt otherwise.
std::optional<std::string> result_of(const sparkplug::Payload& ddata, std::string_view points);

}  // namespace drivegate::cli
