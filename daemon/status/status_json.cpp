// GET /api/v1/status (docs/http.md), written straight into one string: fmt for the numbers, no
// stream and no temporary string per value (the event loop waits while it is written).
#include <fmt/compile.h>
#include <fmt/format.h>

#include <cmath>
#include <iterator>

#include "base/device_text.h"
#include "base/json.h"
#include "status/status_view.h"

namespace drivegate {

namespace {

// A typical document (five drives, one of them with 125 parameters) is 17 KB.
constexpr std::size_t kJsonReserve = 32 * 1024;

void append_json_value(std::string& out, const Value& v) {
  if (const auto* i = std::get_if<std::int64_t>(&v)) {
    out += fmt::format_int(*i).c_str();
  } else if (const auto* d = std::get_if<double>(&v)) {
    if (!std::isfinite(*d)) {
      out += "null";
    } else {
      fmt::format_to(std::back_inserter(out), FMT_COMPILE("{:.6g}"), *d);  // as printf's %.6g
    }
  } else if (const auto* s = std::get_if<std::string>(&v)) {
    // A string point's text, whole, as the device gave it but for the bytes JSON cannot carry.
    std::string text;
    append_device_text(text, *s);
    append_json_string(out, text);
  } else {
    out += "null";
  }
}

std::string_view boolean(bool b) {
  return b ? "true" : "false";
}

void device_json(std::string& out, Device& d, std::vector<PointValue>& values) {
  const auto& cfg = d.config();
  point_values(d, Clock::now(), values);
  out += "{\"name\": ";
  append_json_string(out, cfg.name);
  out += ", \"adapter\": ";
  append_json_string(out, cfg.adapter);
  out += ", \"unit\": ";
  out += fmt::format_int(cfg.unit_id).c_str();
  out += ", \"bus\": ";
  append_json_string(out, cfg.bus);
  out += ", \"online\": ";
  out += boolean(d.online());
  out += ", \"comm_lost\": ";
  out += boolean(d.comm_lost());
  out += ", \"failsafe_latched\": ";
  out += boolean(d.failsafe_latched());
  const WriteStats& ws = d.write_stats();
  fmt::format_to(std::back_inserter(out),
                 ", \"writes\": {{\"in_flight\": {}, \"busy\": {}, \"coalesced\": {}, "
                 "\"refused_failsafe\": {}}}, \"late_bytes\": {}",
                 d.writes_in_flight(), ws.busy, ws.coalesced, ws.refused_failsafe,
                 d.line().counters.late_bytes);

  out += ", \"status_bits\": [";
  bool first = true;
  for (const auto& [p, v] : values) {
    // PointSource::status_bit: the index is the StatusBit.
    if (p->source != PointSource::status_bit || as_double(v) == 0) continue;
    if (!first) out += ", ";
    first = false;
    append_json_string(out, kStatusBitNames.at(p->index));
  }
  out += "], \"common\": {";
  first = true;
  for (const auto& [p, v] : values) {
    if (!p->common() || p->source == PointSource::status_bit) continue;
    if (!first) out += ", ";
    first = false;
    append_json_string(out, p->spec.name);
    out += ": ";
    append_json_value(out, v);
  }
  out += "}, \"labels\": {";
  first = true;
  for (const auto& [p, v] : values) {
    if (!p->common() || p->source == PointSource::status_bit) continue;
    const std::string_view label = label_of(p->spec, v);
    if (label.empty()) continue;
    if (!first) out += ", ";
    first = false;
    append_json_string(out, p->spec.name);
    out += ": ";
    append_json_string(out, label);
  }
  out += "}, \"points\": [";
  first = true;
  for (const auto& [p, v] : values) {
    if (p->common()) continue;
    if (!first) out += ", ";
    first = false;
    out += "{\"name\": ";
    append_json_string(out, p->spec.name);
    out += ", \"value\": ";
    append_json_value(out, v);
    out += ", \"unit\": ";
    append_json_string(out, p->spec.unit);
    const std::string_view label = label_of(p->spec, v);
    if (!label.empty()) {
      out += ", \"label\": ";
      append_json_string(out, label);
    }
    out += '}';
  }
  out += "]}";
}

void bus_json(std::string& out, const Bus& b) {
  const auto& n = b.counters();
  out += "{\"name\": ";
  append_json_string(out, b.config().name);
  out += ", \"port\": ";
  append_json_string(out, b.config().port);
  fmt::format_to(std::back_inserter(out),
                 ", \"open\": {}, \"baud\": {}, \"exchanges\": {}, \"timeouts\": {}, "
                 "\"retries\": {}, \"echo_errors\": {}, \"noise_bytes\": {}, \"late_bytes\": {}, "
                 "\"reopens\": {}, \"bytes_sent\": {}, \"bytes_received\": {}, "
                 "\"line_busy_seconds\": {:.6f}}}",
                 boolean(b.is_open()), b.config().baud, n.exchanges, n.timeouts, n.retries,
                 n.echo_errors, n.noise_bytes, n.late_bytes, n.reopens, n.bytes_sent,
                 n.bytes_received, line_busy_seconds(b));
}

void listener_json(std::string& out, const modbus::Server& server, std::size_t i) {
  const auto& o = server.listener(i);
  const auto s = server.listener_stats(i);
  out += "{\"address\": ";
  append_json_string(out, fmt::format("{}:{}", o.host, server.port(i)));
  fmt::format_to(std::back_inserter(out),
                 ", \"tls\": {}, \"access\": ", boolean(o.policy.tls.has_value()));
  append_json_string(out, to_string(o.policy.access));
  out += ", \"word_order\": ";
  append_json_string(out, to_string(o.policy.word_order));
  out += ", \"allow\": [";
  bool first = true;
  for (const auto& r : o.policy.allow) {
    if (!first) out += ", ";
    first = false;
    append_json_string(out, r.to_string());
  }
  fmt::format_to(std::back_inserter(out),
                 "], \"clients\": {}, \"max_clients\": {}, \"accepted\": {}, \"refused\": {}, "
                 "\"evicted\": {}, \"not_allowed\": {}, \"tls_handshake_failures\": {}, "
                 "\"tls_handshakes_limited\": {}, \"writes_denied\": {}}}",
                 s.connections_active, o.policy.max_clients.value_or(server.limits().max_clients),
                 s.connections_accepted, s.connections_refused, s.connections_evicted,
                 s.connections_not_allowed, s.tls_handshake_failures, s.tls_handshakes_limited,
                 s.writes_denied);
}

void serial_json(std::string& out, const SerialListenerView& l) {
  const auto& c = l.counters;
  out += "{\"port\": ";
  append_json_string(out, l.port);
  out += ", \"framing\": ";
  append_json_string(out, l.framing);
  out += ", \"access\": ";
  append_json_string(out, to_string(l.access));
  fmt::format_to(std::back_inserter(out),
                 ", \"open\": {}, \"reopens\": {}, \"bytes_received\": {}, \"frames\": {}, "
                 "\"crc_errors\": {}, \"exceptions\": {}, \"requests\": {}, "
                 "\"not_answered\": {}, \"busy\": {}, \"overruns\": {}, \"broken_frames\": {}, "
                 "\"other_units\": {}, \"broadcasts\": {}, \"broadcasts_refused\": {}, "
                 "\"accepted_then_failed\": {}}}",
                 boolean(l.open), l.reopens, l.bytes_received, c.bus_messages, c.bus_comm_errors,
                 c.bus_exception_errors, c.server_messages, c.server_no_response, c.server_busy,
                 c.bus_char_overruns, c.broken_frames, c.other_units, c.broadcasts,
                 c.broadcasts_refused, c.write_timeouts);
}

void mqtt_json(std::string& out, const mqtt::NorthboundStatus& m) {
  out += ",\n\"mqtt\": {\"broker\": ";
  append_json_string(out, m.broker);
  fmt::format_to(std::back_inserter(out),
                 ", \"broker_index\": {}, \"brokers\": {}, \"broker_switches\": {}", m.broker_index,
                 m.brokers, m.broker_switches);
  out += ", \"session\": ";
  append_json_string(out, m.session);
  fmt::format_to(std::back_inserter(out),
                 ", \"connected\": {}, \"bd_seq\": {}, \"connects\": {}, \"losses\": {}, "
                 "\"sessions_lost\": {}, \"messages\": {}, \"births\": {}, \"commands\": {}, "
                 "\"commands_retained\": {}, \"rebirths_coalesced\": {}, \"last_error\": ",
                 m.connected, m.bd_seq, m.connects, m.losses, m.sessions_lost, m.messages, m.births,
                 m.commands, m.commands_retained, m.rebirths_coalesced);
  append_json_string(out, m.last_error);
  const mqtt::StoreStats& st = m.store;
  fmt::format_to(std::back_inserter(out),
                 ", \"store\": {{\"enabled\": {}, \"records\": {}, \"bytes\": {}, "
                 "\"oldest_ms\": {}, \"kept\": {}, \"replayed\": {}, \"dropped_size\": {}, "
                 "\"dropped_age\": {}, \"dropped_corrupt_bytes\": {}, \"dropped_lost\": {}, "
                 "\"refused\": {}, \"replay_dropped\": {}}}",
                 st.enabled, st.records, st.bytes,
                 st.oldest_ms ? std::to_string(*st.oldest_ms) : std::string("null"), st.kept,
                 st.replayed, st.dropped_size, st.dropped_age, st.dropped_corrupt, st.dropped_lost,
                 st.refused, st.replay_dropped);
  out += '}';
}

void http_json(std::string& out, const http::HttpStats& h, std::size_t clients) {
  fmt::format_to(std::back_inserter(out),
                 ",\n\"http\": {{\"clients\": {}, \"accepted\": {}, \"not_allowed\": {}, "
                 "\"refused\": {}, \"requests\": {}, \"bad_requests\": {}, \"timeouts\": {}, "
                 "\"captures\": {}, \"captures_refused\": {}, \"requests_paced\": {}}}",
                 clients, h.accepted, h.not_allowed, h.refused, h.requests, h.bad_requests,
                 h.timeouts, h.captures, h.captures_refused, h.requests_paced);
}

}  // namespace

void status_json(const StatusView& view, std::string& out) {
  out += "{\"version\": ";
  append_json_string(out, view.version);
  fmt::format_to(std::back_inserter(out), ", \"started\": {:.3f}, \"now\": {:.3f}",
                 view.started_unix, view.now_unix);
  out += ", \"restart_needed\": [";
  if (view.restart_needed != nullptr) {
    for (std::size_t i = 0; i < view.restart_needed->size(); ++i) {
      if (i > 0) out += ", ";
      append_json_string(out, (*view.restart_needed)[i]);
    }
  }
  out += "],\n\"devices\": [";
  bool first = true;
  std::vector<PointValue> values;  // one device's at a time, its room kept for the next
  for (const auto& d : view.gateway.devices()) {
    out += first ? "\n" : ",\n";
    first = false;
    device_json(out, *d, values);
  }
  out += "],\n\"buses\": [";
  first = true;
  for (const auto& b : view.gateway.buses()) {
    out += first ? "\n" : ",\n";
    first = false;
    bus_json(out, *b);
  }
  out += "],\n\"listeners\": [";
  for (std::size_t i = 0; i < view.server.listener_count(); ++i) {
    out += i == 0 ? "\n" : ",\n";
    listener_json(out, view.server, i);
  }
  out += "],\n\"serial_listeners\": [";
  for (std::size_t i = 0; i < view.serial.size(); ++i) {
    out += i == 0 ? "\n" : ",\n";
    serial_json(out, view.serial[i]);
  }
  const auto s = view.server.stats();
  fmt::format_to(std::back_inserter(out),
                 "],\n\"modbus\": {{\"clients\": {}, \"requests\": {}, \"malformed\": {}, "
                 "\"refused\": {}}}",
                 view.server.client_count(), s.requests, s.malformed, s.connections_refused);
  if (view.mqtt != nullptr) mqtt_json(out, *view.mqtt);
  if (view.http) http_json(out, *view.http, view.http_clients);
  out += "}\n";
}

std::string status_json(const StatusView& view) {
  std::string out;
  out.reserve(kJsonReserve);
  status_json(view, out);
  return out;
}

}  // namespace drivegate
