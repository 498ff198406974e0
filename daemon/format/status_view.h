// What the status page, its JSON and the Prometheus metrics are made of: the running gateway
// (its devices' register images, read as a Modbus client reads them, and its buses' counters),
// the Modbus server's listeners and counters, and the process's identity. The documents are
// rendered from the register map's own rows (gateway/common_block.h), so a counter added there
// appears in both with no change here.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "drivegate/point.h"
#include "gateway/gateway.h"
#include "modbus/server.h"

namespace drivegate {

struct StatusView {
  Gateway& gateway;
  const modbus::Server& server;
  std::string version;
  double started_unix = 0;  // process start, seconds since the epoch
  double now_unix = 0;
};

// Every point of `device` (the common block, then the adapter's), its value decoded from the
// register image as a client in the map's word order reads it.
std::vector<std::pair<const MappedPoint*, Value>> point_values(Device& device);

// The name of `value` in the point's labels, or "" (a value without a name, or a bit field).
std::string label_of(const PointSpec& spec, const Value& value);

// Seconds of line time the bus's bytes took (sent and received, an echo once): its rate is the
// line's utilisation.
double line_busy_seconds(const Bus& bus);

std::string status_json(const StatusView& view);
std::string metrics_text(const StatusView& view);

}  // namespace drivegate
