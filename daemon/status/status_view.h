// What the status page, its JSON and the Prometheus metrics are made of: the running gateway
// (its devices' register images, read as a Modbus client reads them, and its buses' counters),
// the Modbus server's listeners and counters, and the process's identity. The documents are
// rendered from the register map's own rows (gateway/common_block.h), so a counter added there
// appears in both with no change here.
//
// They are rendered on the event loop that also answers Modbus, so a render is time a Modbus
// request that arrives meanwhile waits (docs/performance.md, bench/http_load.sh): each document is
// written into one string, reserved up front, with no temporary string per value, and each
// device's image is read a table at a time, not a point at a time.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "drivegate/point.h"
#include "gateway/gateway.h"
#include "gateway/point_values.h"
#include "history/command_audit.h"
#include "history/event_log.h"
#include "http/http_stats.h"
#include "modbus/diagnostics.h"
#include "modbus/server.h"
#include "mqtt/northbound_status.h"

namespace drivegate {

// A serial listener as the documents show it (docs/serial-listeners.md).
struct SerialListenerView {
  std::string port;     // its line: a device, or tcp:// / rfc2217://
  std::string framing;  // "rtu" or "ascii"
  AccessLevel access = AccessLevel::read;
  bool open = false;
  std::uint64_t bytes_received = 0;
  std::uint64_t reopens = 0;
  modbus::SerialCounters counters;
};

struct StatusView {
  Gateway& gateway;
  const modbus::Server& server;
  std::string version;
  double started_unix = 0;  // process start, seconds since the epoch
  double now_unix = 0;
  const mqtt::NorthboundStatus* mqtt = nullptr;  // [mqtt] off: none
  std::optional<http::HttpStats> http{};         // the HTTP side serving these documents, if any
  std::size_t http_clients = 0;
  // What the configuration file asks and only a restart applies; none: nothing.
  const std::vector<std::string>* restart_needed = nullptr;
  // Every write by source and result (history/command_audit.h), and the event history; none in
  // a document rendered without them.
  const CommandCounts* commands = nullptr;
  const EventLog* history = nullptr;
  std::vector<SerialListenerView> serial{};  // the RTU / ASCII listeners on serial lines
};

// Seconds of line time the bus's bytes took (sent and received, an echo once): its rate is the
// line's utilisation.
double line_busy_seconds(const Bus& bus);

// The documents, appended to `out`; the forms that return them reserve room for a typical one.
void status_json(const StatusView& view, std::string& out);
void metrics_text(const StatusView& view, std::string& out);
std::string status_json(const StatusView& view);
std::string metrics_text(const StatusView& view);

}  // namespace drivegate
