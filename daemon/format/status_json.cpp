#include <cmath>
#include <cstdio>
#include <sstream>

#include "format/json.h"
#include "format/status_view.h"

namespace drivegate {

namespace {

std::string json_value(const Value& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) return std::to_string(*i);
  if (const auto* d = std::get_if<double>(&v)) {
    if (!std::isfinite(*d)) return "null";
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", *d);
    return buf;
  }
  if (const auto* s = std::get_if<std::string>(&v)) return json_string(*s);
  return "null";
}

const char* boolean(bool b) {
  return b ? "true" : "false";
}

void device_json(std::ostringstream& out, Device& d) {
  const auto& cfg = d.config();
  const auto values = point_values(d);
  out << "{\"name\": " << json_string(cfg.name) << ", \"adapter\": " << json_string(cfg.adapter)
      << ", \"unit\": " << int{cfg.unit_id} << ", \"bus\": " << json_string(cfg.bus)
      << ", \"online\": " << boolean(d.online()) << ", \"comm_lost\": " << boolean(d.comm_lost())
      << ", \"failsafe_latched\": " << boolean(d.failsafe_latched());
  std::string common;
  std::string points;
  std::string labels;
  std::string bits;
  for (const auto& [p, v] : values) {
    if (p->source == PointSource::status_bit) {
      if (as_double(v) != 0) {
        // PointSource::status_bit: the index is the StatusBit.
        bits += (bits.empty() ? "" : ", ") + json_string(kStatusBitNames.at(p->index));
      }
      continue;
    }
    const std::string label = label_of(p->spec, v);
    if (p->common()) {
      common += (common.empty() ? "" : ", ") + json_string(p->spec.name) + ": " + json_value(v);
      if (!label.empty()) {
        labels +=
            (labels.empty() ? "" : ", ") + json_string(p->spec.name) + ": " + json_string(label);
      }
    } else {
      points += std::string(points.empty() ? "" : ", ") +
                "{\"name\": " + json_string(p->spec.name) + ", \"value\": " + json_value(v) +
                ", \"unit\": " + json_string(p->spec.unit) +
                (label.empty() ? "" : ", \"label\": " + json_string(label)) + "}";
    }
  }
  out << ", \"status_bits\": [" << bits << "], \"common\": {" << common << "}, \"labels\": {"
      << labels << "}, \"points\": [" << points << "]}";
}

void bus_json(std::ostringstream& out, const Bus& b) {
  const auto& n = b.counters();
  char busy[32];
  std::snprintf(busy, sizeof busy, "%.6f", line_busy_seconds(b));
  out << "{\"name\": " << json_string(b.config().name)
      << ", \"port\": " << json_string(b.config().port) << ", \"open\": " << boolean(b.is_open())
      << ", \"baud\": " << b.config().baud << ", \"exchanges\": " << n.exchanges
      << ", \"timeouts\": " << n.timeouts << ", \"retries\": " << n.retries
      << ", \"echo_errors\": " << n.echo_errors << ", \"noise_bytes\": " << n.noise_bytes
      << ", \"reopens\": " << n.reopens << ", \"bytes_sent\": " << n.bytes_sent
      << ", \"bytes_received\": " << n.bytes_received << ", \"line_busy_seconds\": " << busy << "}";
}

void listener_json(std::ostringstream& out, const modbus::Server& server, std::size_t i) {
  const auto& o = server.listener(i);
  const auto& s = server.listener_stats(i);
  std::string allow;
  for (const auto& r : o.policy.allow) {
    allow += (allow.empty() ? "" : ", ") + json_string(r.to_string());
  }
  out << "{\"address\": " << json_string(o.host + ":" + std::to_string(server.port(i)))
      << ", \"tls\": " << boolean(o.policy.tls.has_value())
      << ", \"access\": " << json_string(to_string(o.policy.access))
      << ", \"word_order\": " << json_string(to_string(o.policy.word_order)) << ", \"allow\": ["
      << allow << "], \"clients\": " << s.connections_active
      << ", \"accepted\": " << s.connections_accepted
      << ", \"not_allowed\": " << s.connections_not_allowed
      << ", \"tls_handshake_failures\": " << s.tls_handshake_failures
      << ", \"writes_denied\": " << s.writes_denied << "}";
}

}  // namespace

std::string status_json(const StatusView& view) {
  std::ostringstream out;
  char times[96];
  std::snprintf(times, sizeof times, "\"started\": %.3f, \"now\": %.3f", view.started_unix,
                view.now_unix);
  out << "{\"version\": " << json_string(view.version) << ", " << times << ",\n\"devices\": [";
  bool first = true;
  for (const auto& d : view.gateway.devices()) {
    out << (first ? "\n" : ",\n");
    first = false;
    device_json(out, *d);
  }
  out << "],\n\"buses\": [";
  first = true;
  for (const auto& b : view.gateway.buses()) {
    out << (first ? "\n" : ",\n");
    first = false;
    bus_json(out, *b);
  }
  out << "],\n\"listeners\": [";
  for (std::size_t i = 0; i < view.server.listener_count(); ++i) {
    out << (i == 0 ? "\n" : ",\n");
    listener_json(out, view.server, i);
  }
  const auto& s = view.server.stats();
  out << "],\n\"modbus\": {\"clients\": " << view.server.client_count()
      << ", \"requests\": " << s.requests << ", \"malformed\": " << s.malformed
      << ", \"refused\": " << s.connections_refused << "}}\n";
  return out.str();
}

}  // namespace drivegate
