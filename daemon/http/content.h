// What the HTTP side serves, and the one seam with the rest of the daemon (as backend.h is for
// Modbus): the daemon renders each document from the same register image and counters a Modbus
// client sees, at the moment it is asked for, on the event loop. Read-only: nothing here writes.
#pragma once

#include <string>

namespace drivegate::http {

class Content {
 public:
  virtual ~Content() = default;
  // GET /api/v1/status: devices, buses, listeners and clients (docs/http.md).
  virtual std::string status_json() = 0;
  // GET /metrics: Prometheus text exposition format 0.0.4.
  virtual std::string metrics() = 0;
  // GET /api/v1/regmap: the register map, as `drivegate regmap --format json` prints it.
  virtual std::string regmap_json() = 0;
};

}  // namespace drivegate::http
