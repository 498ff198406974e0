// Prometheus text exposition format 0.0.4: one HELP and one TYPE line per family, then its
// samples; counters end in _total; label values escape backslash, double quote and newline.
// Written straight into one string (the event loop waits while it is written): fmt for the
// numbers, each device's labels written once, no stream and no temporary string per sample.
#include <fmt/compile.h>
#include <fmt/format.h>

#include <cmath>
#include <iterator>

#include "status/status_view.h"

namespace drivegate {

namespace {

// A typical document (five drives) is 16 KB.
constexpr std::size_t kReserve = 32 * 1024;

void append_escaped(std::string& out, std::string_view v) {
  for (const char c : v) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
}

// As printf's %.17g (a double read back as itself). Counters and most gauges are whole numbers:
// those are written as integers, the same digits %.17g gives, without its cost.
void append_number(std::string& out, double v) {
  if (std::isnan(v)) {
    out += "NaN";
  } else if (v == std::trunc(v) && std::fabs(v) < 1e15) {
    out += fmt::format_int(static_cast<long long>(v)).c_str();
    if (v == 0 && std::signbit(v)) out.insert(out.size() - 1, 1, '-');  // %.17g: "-0"
  } else {
    fmt::format_to(std::back_inserter(out), FMT_COMPILE("{:.17g}"), v);
  }
}

class Writer {
 public:
  explicit Writer(std::string& out) : out_(out) {}
  void family(std::string_view name, std::string_view type, std::string_view help) {
    out_ += "# HELP ";
    out_ += name;
    out_ += ' ';
    out_ += help;
    out_ += "\n# TYPE ";
    out_ += name;
    out_ += ' ';
    out_ += type;
    out_ += '\n';
  }
  // A family of one sample without labels.
  void single(std::string_view name, std::string_view type, std::string_view help, double value) {
    family(name, type, help);
    sample(name, "", value);
  }
  // `labels` as written between the braces ("" for none), then `extra` (",name=\"value\"")
  void sample(std::string_view name, std::string_view labels, double value,
              std::string_view extra = {}) {
    out_ += name;
    if (!labels.empty() || !extra.empty()) {
      out_ += '{';
      out_ += labels;
      out_ += extra;
      out_ += '}';
    }
    out_ += ' ';
    append_number(out_, value);
    out_ += '\n';
  }

 private:
  std::string& out_;
};

std::string device_labels(const Device& d) {
  const auto& c = d.config();
  std::string out = "device=\"";
  append_escaped(out, c.name);
  out += "\",adapter=\"";
  append_escaped(out, c.adapter);
  fmt::format_to(std::back_inserter(out), "\",unit=\"{}\",bus=\"", c.unit_id);
  append_escaped(out, c.bus);
  out += '"';
  return out;
}

// Common rows that are per bus (bus_*) are exported once per bus, not once per device.
bool per_bus(const std::string& name) {
  return name.starts_with("bus_");
}

void device_metrics(Writer& w, const StatusView& view) {
  struct Row {
    std::string labels;
    std::vector<PointValue> values;
    Device* device;
  };
  std::vector<Row> rows;
  rows.reserve(view.gateway.devices().size());
  for (const auto& d : view.gateway.devices()) {
    Row& r = rows.emplace_back(Row{device_labels(*d), {}, d.get()});
    point_values(*d, Clock::now(), r.values);
  }
  w.family("drivegate_device_online", "gauge",
           "1 when the drive answers and its protocol is up (status bit online)");
  for (const Row& r : rows) w.sample("drivegate_device_online", r.labels, r.device->online());
  w.family("drivegate_device_comm_lost", "gauge", "1 when the drive stopped answering");
  for (const Row& r : rows) {
    w.sample("drivegate_device_comm_lost", r.labels, r.device->comm_lost());
  }
  w.family("drivegate_device_failsafe_latched", "gauge",
           "1 while the PLC-loss failsafe holds the drive stopped");
  for (const Row& r : rows) {
    w.sample("drivegate_device_failsafe_latched", r.labels, r.device->failsafe_latched());
  }
  // The write queue (docs/safety.md, "Fair line time") and late replies.
  const auto each = [&](std::string_view family, std::string_view type, std::string_view help,
                        auto f) {
    w.family(family, type, help);
    for (const Row& r : rows) w.sample(family, r.labels, static_cast<double>(f(*r.device)));
  };
  each("drivegate_device_writes_in_flight", "gauge",
       "writes waiting for the drive or being carried out (at most 4 queued, stops apart)",
       [](const Device& d) { return d.writes_in_flight(); });
  each("drivegate_device_writes_busy_total", "counter",
       "writes refused with exception 06: the device's write queue was full",
       [](const Device& d) { return d.write_stats().busy; });
  each("drivegate_device_writes_coalesced_total", "counter",
       "writes equal to the one queued before them, answered with it",
       [](const Device& d) { return d.write_stats().coalesced; });
  each("drivegate_device_runs_refused_failsafe_total", "counter",
       "runs refused while the failsafe was latched, from a source that cannot clear it",
       [](const Device& d) { return d.write_stats().refused_failsafe; });
  each("drivegate_device_late_bytes_total", "counter",
       "bytes of replies that came after their timeout, dropped",
       [](const Device& d) { return d.line().counters.late_bytes; });
  // Every numeric common point (gateway/common_block.h): gauges, counters as _total.
  if (rows.empty()) return;
  std::string name;
  for (std::size_t i = 0; i < rows.front().values.size(); ++i) {
    const MappedPoint* p = rows.front().values[i].first;
    if (!p->common() || p->source == PointSource::status_bit || per_bus(p->spec.name)) continue;
    const CommonRow* row = p->row();
    if (row == nullptr || p->spec.name == "status") continue;  // the bits are the gauges above
    const bool age = p->spec.name == "data_age_ms";
    name = "drivegate_device_";
    name += age ? std::string_view("data_age_seconds") : std::string_view(p->spec.name);
    if (row->counter) name += "_total";
    w.family(name, row->counter ? "counter" : "gauge",
             age ? "seconds since the last reply carrying the drive's state (NaN: never)"
                 : row->description);
    for (const Row& r : rows) {
      // Every device has the same common block, in the same order.
      const Value& v = r.values.at(i).second;
      double x = as_double(v);
      if (age) x = x >= 4294967295.0 ? NAN : x / 1000.0;  // never heard: NaN
      w.sample(name, r.labels, x);
    }
  }
}

template <typename F>
void bus_family(Writer& w, const std::vector<std::string>& labels, const StatusView& view,
                std::string_view name, std::string_view type, std::string_view help, F f) {
  w.family(name, type, help);
  const auto& buses = view.gateway.buses();
  for (std::size_t i = 0; i < buses.size(); ++i) {
    w.sample(name, labels[i], static_cast<double>(f(*buses[i])));
  }
}

void bus_metrics(Writer& w, const StatusView& view) {
  const auto& buses = view.gateway.buses();
  std::vector<std::string> labels;
  labels.reserve(buses.size());
  for (const auto& b : buses) {
    std::string& l = labels.emplace_back("bus=\"");
    append_escaped(l, b->config().name);
    l += '"';
  }
  const auto family = [&](std::string_view name, std::string_view type, std::string_view help,
                          auto f) { bus_family(w, labels, view, name, type, help, f); };
  family("drivegate_bus_open", "gauge", "1 while the port (or connection) is open",
         [](const Bus& b) { return b.is_open() ? 1.0 : 0.0; });
  family("drivegate_bus_transactions_total", "counter", "request / reply transactions begun",
         [](const Bus& b) { return b.counters().exchanges; });
  family("drivegate_bus_timeouts_total", "counter", "attempts that got no reply in time",
         [](const Bus& b) { return b.counters().timeouts; });
  family("drivegate_bus_retries_total", "counter", "frames sent again",
         [](const Bus& b) { return b.counters().retries; });
  family("drivegate_bus_echo_errors_total", "counter",
         "one-wire echoes that differed from what was sent, or never came",
         [](const Bus& b) { return b.counters().echo_errors; });
  family("drivegate_bus_noise_bytes_total", "counter", "bytes on the line nobody asked for",
         [](const Bus& b) { return b.counters().noise_bytes; });
  family("drivegate_bus_reopens_total", "counter", "times the port was reopened",
         [](const Bus& b) { return b.counters().reopens; });
  family("drivegate_bus_late_bytes_total", "counter",
         "bytes of replies that came after their timeout, dropped in the guard time",
         [](const Bus& b) { return b.counters().late_bytes; });
  w.family("drivegate_bus_bytes_total", "counter", "bytes written to and read from the line");
  for (std::size_t i = 0; i < buses.size(); ++i) {
    w.sample("drivegate_bus_bytes_total", labels[i],
             static_cast<double>(buses[i]->counters().bytes_sent), ",direction=\"sent\"");
    w.sample("drivegate_bus_bytes_total", labels[i],
             static_cast<double>(buses[i]->counters().bytes_received), ",direction=\"received\"");
  }
  family("drivegate_bus_line_busy_seconds_total", "counter",
         "line time the bytes took (its rate is the line's utilisation)",
         [](const Bus& b) { return line_busy_seconds(b); });
}

void listener_metrics(Writer& w, const StatusView& view) {
  const auto& s = view.server;
  std::vector<std::string> labels;
  labels.reserve(s.listener_count());
  for (std::size_t i = 0; i < s.listener_count(); ++i) {
    std::string& l = labels.emplace_back("listener=\"");
    append_escaped(l, s.listener(i).host);
    fmt::format_to(std::back_inserter(l), ":{}\"", s.port(i));
  }
  // Each listener's counters, composed once for every family below.
  std::vector<modbus::ListenerStats> counted;
  counted.reserve(s.listener_count());
  for (std::size_t i = 0; i < s.listener_count(); ++i) counted.push_back(s.listener_stats(i));
  const auto family = [&](std::string_view name, std::string_view type, std::string_view help,
                          auto f) {
    w.family(name, type, help);
    for (std::size_t i = 0; i < counted.size(); ++i) {
      w.sample(name, labels[i], static_cast<double>(f(counted[i])));
    }
  };
  family("drivegate_modbus_connections", "gauge", "Modbus TCP clients connected",
         [](const auto& l) { return l.connections_active; });
  family("drivegate_modbus_connections_accepted_total", "counter", "connections served",
         [](const auto& l) { return l.connections_accepted; });
  w.family("drivegate_modbus_max_clients", "gauge", "the listener's connection slots");
  for (std::size_t i = 0; i < s.listener_count(); ++i) {
    w.sample(
        "drivegate_modbus_max_clients", labels[i],
        static_cast<double>(s.listener(i).policy.max_clients.value_or(s.limits().max_clients)));
  }
  family("drivegate_modbus_connections_refused_total", "counter",
         "connections closed at accept: the listener full, no idle read-only client to give way",
         [](const auto& l) { return l.connections_refused; });
  family("drivegate_modbus_connections_evicted_total", "counter",
         "idle read-only connections closed to make room for a new client on a full listener",
         [](const auto& l) { return l.connections_evicted; });
  family("drivegate_modbus_connections_not_allowed_total", "counter",
         "connections closed at accept: address not in the allow list",
         [](const auto& l) { return l.connections_not_allowed; });
  family("drivegate_modbus_tls_handshake_failures_total", "counter",
         "TLS handshakes that failed (certificate refused, not TLS, too slow)",
         [](const auto& l) { return l.tls_handshake_failures; });
  family("drivegate_modbus_tls_handshakes_limited_total", "counter",
         "TLS connections closed at accept: their address past tls_handshakes_per_s",
         [](const auto& l) { return l.tls_handshakes_limited; });
  family("drivegate_modbus_writes_denied_total", "counter",
         "writes refused with exception 01: beyond the connection's access level",
         [](const auto& l) { return l.writes_denied; });
  family("drivegate_modbus_received_bytes_total", "counter",
         "bytes the listener's clients sent (TLS: after decryption)",
         [](const auto& l) { return l.bytes_received; });
  const auto all = s.stats();  // every listener's together
  w.single("drivegate_modbus_malformed_total", "counter",
           "connections closed on a frame that is not Modbus TCP",
           static_cast<double>(all.malformed));
  w.single("drivegate_modbus_frame_timeouts_total", "counter",
           "connections closed with a partial frame left unfinished",
           static_cast<double>(all.frame_timeouts));
  w.single("drivegate_modbus_writes_unanswered_total", "counter",
           "writes that settled after their client had gone, so it was never told the result",
           static_cast<double>(all.writes_unanswered));
  char extra[32];
  w.family("drivegate_modbus_requests_total", "counter", "requests, by function code");
  for (std::size_t i = 0; i < s.listener_count(); ++i) {
    const auto& r = counted[i].by_function;
    for (std::size_t fc = 0; fc < r.size(); ++fc) {
      if (r[fc] == 0) continue;
      const auto end = fc == 0 ? fmt::format_to(extra, ",function=\"other\"")
                               : fmt::format_to(extra, ",function=\"0x{:02X}\"", fc);
      w.sample("drivegate_modbus_requests_total", labels[i], static_cast<double>(r[fc]),
               std::string_view(extra, static_cast<std::size_t>(end - extra)));
    }
  }
  w.family("drivegate_modbus_exceptions_total", "counter", "exception responses, by code");
  for (std::size_t i = 0; i < s.listener_count(); ++i) {
    const auto& e = counted[i].exceptions;
    for (std::size_t code = 1; code < e.size(); ++code) {
      if (e[code] == 0) continue;
      const auto end = fmt::format_to(extra, ",code=\"0x{:02X}\"", code);
      w.sample("drivegate_modbus_exceptions_total", labels[i], static_cast<double>(e[code]),
               std::string_view(extra, static_cast<std::size_t>(end - extra)));
    }
  }
}

// The Sparkplug B northbound ([mqtt], docs/mqtt.md).
void mqtt_metrics(Writer& w, const mqtt::NorthboundStatus& m) {
  w.single("drivegate_mqtt_connected", "gauge", "1 while the session with the broker is up",
           m.connected ? 1 : 0);
  w.single("drivegate_mqtt_online", "gauge",
           "1 once the births are out (and the primary host, if any, is online)",
           m.session == "online" ? 1 : 0);
  w.single("drivegate_mqtt_bdseq", "gauge", "the session's Sparkplug bdSeq", m.bd_seq);
  w.single("drivegate_mqtt_connects_total", "counter", "sessions begun with the broker",
           static_cast<double>(m.connects));
  w.single("drivegate_mqtt_connection_losses_total", "counter",
           "connection attempts that failed and sessions lost", static_cast<double>(m.losses));
  w.single("drivegate_mqtt_messages_total", "counter", "Sparkplug messages published",
           static_cast<double>(m.messages));
  w.single("drivegate_mqtt_device_births_total", "counter", "DBIRTH messages published",
           static_cast<double>(m.births));
  w.single("drivegate_mqtt_commands_total", "counter",
           "DCMD writes carried out, whatever the outcome", static_cast<double>(m.commands));
  w.single("drivegate_mqtt_commands_retained_total", "counter",
           "NCMD and DCMD messages never carried out: retained by the broker, not live",
           static_cast<double>(m.commands_retained));
  w.single("drivegate_mqtt_rebirths_coalesced_total", "counter",
           "rebirth requests answered by one rebirth a few seconds later",
           static_cast<double>(m.rebirths_coalesced));
}

// The HTTP side itself ([http]): the scrapers and status pages reading these documents.
void http_metrics(Writer& w, const http::HttpStats& h, std::size_t clients) {
  const auto count = [](std::uint64_t n) { return static_cast<double>(n); };
  w.single("drivegate_http_connections", "gauge", "HTTP clients connected",
           static_cast<double>(clients));
  w.single("drivegate_http_connections_accepted_total", "counter", "HTTP connections served",
           count(h.accepted));
  w.single("drivegate_http_connections_not_allowed_total", "counter",
           "HTTP connections closed at accept: address not in [http] allow", count(h.not_allowed));
  w.single("drivegate_http_connections_refused_total", "counter",
           "HTTP connections closed at accept: too many clients", count(h.refused));
  w.single("drivegate_http_requests_total", "counter", "HTTP requests answered from a route",
           count(h.requests));
  w.single("drivegate_http_bad_requests_total", "counter",
           "HTTP requests refused as malformed or too large (400, 431)", count(h.bad_requests));
  w.single("drivegate_http_timeouts_total", "counter",
           "HTTP connections closed: no whole request within the request timeout",
           count(h.timeouts));
  w.single("drivegate_http_captures_total", "counter", "bus captures started (/api/v1/capture)",
           count(h.captures));
  w.single("drivegate_http_captures_refused_total", "counter",
           "bus captures refused (503): as many were streaming as may at once",
           count(h.captures_refused));
  w.single("drivegate_http_requests_paced_total", "counter",
           "HTTP requests held back by the per-address rate limit before their answer",
           count(h.requests_paced));
}

}  // namespace

void metrics_text(const StatusView& view, std::string& out) {
  Writer w(out);
  w.family("drivegate_build_info", "gauge", "the running drivegate's version");
  std::string version = "version=\"";
  append_escaped(version, view.version);
  version += '"';
  w.sample("drivegate_build_info", version, 1);
  w.single("process_start_time_seconds", "gauge", "start time of the process since the epoch",
           view.started_unix);
  w.single("drivegate_restart_needed", "gauge",
           "1 while the configuration file asks for what only a restart applies",
           view.restart_needed != nullptr && !view.restart_needed->empty() ? 1 : 0);
  device_metrics(w, view);
  bus_metrics(w, view);
  listener_metrics(w, view);
  if (view.mqtt != nullptr) mqtt_metrics(w, *view.mqtt);
  if (view.http) http_metrics(w, *view.http, view.http_clients);
}

std::string metrics_text(const StatusView& view) {
  std::string out;
  out.reserve(kReserve);
  metrics_text(view, out);
  return out;
}

}  // namespace drivegate
