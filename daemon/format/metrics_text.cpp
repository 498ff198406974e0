// Prometheus text exposition format 0.0.4: one HELP and one TYPE line per family, then its
// samples; counters end in _total; label values escape backslash, double quote and newline.
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

#include "format/status_view.h"

namespace drivegate {

namespace {

std::string escape_label(std::string_view v) {
  std::string out;
  for (const char c : v) {
    if (c == '\\' || c == '"') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out;
}

std::string number(double v) {
  if (std::isnan(v)) return "NaN";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

class Writer {
 public:
  void family(std::string_view name, std::string_view type, std::string_view help) {
    out_ << "# HELP " << name << ' ' << help << "\n# TYPE " << name << ' ' << type << '\n';
  }
  void sample(std::string_view name, const std::string& labels, double value) {
    out_ << name;
    if (!labels.empty()) out_ << '{' << labels << '}';
    out_ << ' ' << number(value) << '\n';
  }
  std::string str() const { return out_.str(); }

 private:
  std::ostringstream out_;
};

std::string device_labels(const Device& d) {
  const auto& c = d.config();
  return "device=\"" + escape_label(c.name) + "\",adapter=\"" + escape_label(c.adapter) +
         "\",unit=\"" + std::to_string(c.unit_id) + "\",bus=\"" + escape_label(c.bus) + "\"";
}

// Common rows that are per bus (bus_*) are exported once per bus, not once per device.
bool per_bus(const std::string& name) {
  return name.starts_with("bus_");
}

void device_metrics(Writer& w, const StatusView& view) {
  struct Row {
    std::string labels;
    std::vector<std::pair<const MappedPoint*, Value>> values;
    Device* device;
  };
  std::vector<Row> rows;
  for (const auto& d : view.gateway.devices()) {
    rows.push_back({device_labels(*d), point_values(*d), d.get()});
  }
  const auto each = [&](const std::function<void(const Row&)>& f) {
    for (const Row& r : rows) f(r);
  };
  w.family("drivegate_device_online", "gauge",
           "1 when the drive answers and its protocol is up (status bit online)");
  each([&](const Row& r) { w.sample("drivegate_device_online", r.labels, r.device->online()); });
  w.family("drivegate_device_comm_lost", "gauge", "1 when the drive stopped answering");
  each([&](const Row& r) {
    w.sample("drivegate_device_comm_lost", r.labels, r.device->comm_lost());
  });
  w.family("drivegate_device_failsafe_latched", "gauge",
           "1 while the PLC-loss failsafe holds the drive stopped");
  each([&](const Row& r) {
    w.sample("drivegate_device_failsafe_latched", r.labels, r.device->failsafe_latched());
  });
  // Every numeric common point (gateway/common_block.h): gauges, counters as _total.
  if (rows.empty()) return;
  for (std::size_t i = 0; i < rows.front().values.size(); ++i) {
    const MappedPoint* p = rows.front().values[i].first;
    if (!p->common() || p->source == PointSource::status_bit || per_bus(p->spec.name)) continue;
    const CommonRow* row = p->row();
    if (row == nullptr || p->spec.name == "status") continue;  // the bits are the gauges above
    const bool age = p->spec.name == "data_age_ms";
    const std::string name = "drivegate_device_" +
                             (age ? std::string("data_age_seconds") : p->spec.name) +
                             (row->counter ? "_total" : "");
    w.family(name, row->counter ? "counter" : "gauge",
             age ? "seconds since the last good frame (NaN: never heard)" : row->description);
    each([&](const Row& r) {
      // Every device has the same common block, in the same order.
      const Value& v = r.values.at(i).second;
      double x = as_double(v);
      if (age) x = x >= 4294967295.0 ? NAN : x / 1000.0;  // never heard: NaN
      w.sample(name, r.labels, x);
    });
  }
}

void bus_metrics(Writer& w, const StatusView& view) {
  const auto& buses = view.gateway.buses();
  const auto labels = [](const Bus& b) { return "bus=\"" + escape_label(b.config().name) + "\""; };
  const auto family = [&](std::string_view name, std::string_view type, std::string_view help,
                          const std::function<double(const Bus&)>& f) {
    w.family(name, type, help);
    for (const auto& b : buses) w.sample(name, labels(*b), f(*b));
  };
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
  w.family("drivegate_bus_bytes_total", "counter", "bytes written to and read from the line");
  for (const auto& b : buses) {
    w.sample("drivegate_bus_bytes_total", labels(*b) + ",direction=\"sent\"",
             static_cast<double>(b->counters().bytes_sent));
    w.sample("drivegate_bus_bytes_total", labels(*b) + ",direction=\"received\"",
             static_cast<double>(b->counters().bytes_received));
  }
  family("drivegate_bus_line_busy_seconds_total", "counter",
         "line time the bytes took (its rate is the line's utilisation)",
         [](const Bus& b) { return line_busy_seconds(b); });
}

void listener_metrics(Writer& w, const StatusView& view) {
  const auto& s = view.server;
  const auto label = [&](std::size_t i) {
    const auto& o = s.listener(i);
    return "listener=\"" + escape_label(o.host) + ":" + std::to_string(s.port(i)) + "\"";
  };
  const auto family = [&](std::string_view name, std::string_view type, std::string_view help,
                          const std::function<double(const modbus::ListenerStats&)>& f) {
    w.family(name, type, help);
    for (std::size_t i = 0; i < s.listener_count(); ++i) {
      w.sample(name, label(i), f(s.listener_stats(i)));
    }
  };
  family("drivegate_modbus_connections", "gauge", "Modbus TCP clients connected",
         [](const auto& l) { return static_cast<double>(l.connections_active); });
  family("drivegate_modbus_connections_accepted_total", "counter", "connections served",
         [](const auto& l) { return static_cast<double>(l.connections_accepted); });
  family("drivegate_modbus_connections_not_allowed_total", "counter",
         "connections closed at accept: address not in the allow list",
         [](const auto& l) { return static_cast<double>(l.connections_not_allowed); });
  family("drivegate_modbus_tls_handshake_failures_total", "counter",
         "TLS handshakes that failed (certificate refused, not TLS, too slow)",
         [](const auto& l) { return static_cast<double>(l.tls_handshake_failures); });
  family("drivegate_modbus_writes_denied_total", "counter",
         "writes refused with exception 01: beyond the connection's access level",
         [](const auto& l) { return static_cast<double>(l.writes_denied); });
  w.family("drivegate_modbus_requests_total", "counter", "requests, by function code");
  for (std::size_t i = 0; i < s.listener_count(); ++i) {
    const auto& r = s.listener_stats(i).requests;
    for (std::size_t fc = 0; fc < r.size(); ++fc) {
      if (r[fc] == 0) continue;
      char code[8];
      std::snprintf(code, sizeof code, "0x%02X", static_cast<unsigned>(fc));
      w.sample("drivegate_modbus_requests_total",
               label(i) + ",function=\"" + (fc == 0 ? std::string("other") : code) + "\"",
               static_cast<double>(r[fc]));
    }
  }
  w.family("drivegate_modbus_exceptions_total", "counter", "exception responses, by code");
  for (std::size_t i = 0; i < s.listener_count(); ++i) {
    const auto& e = s.listener_stats(i).exceptions;
    for (std::size_t code = 1; code < e.size(); ++code) {
      if (e[code] == 0) continue;
      char text[8];
      std::snprintf(text, sizeof text, "0x%02X", static_cast<unsigned>(code));
      w.sample("drivegate_modbus_exceptions_total", label(i) + ",code=\"" + text + "\"",
               static_cast<double>(e[code]));
    }
  }
}

}  // namespace

std::string metrics_text(const StatusView& view) {
  Writer w;
  w.family("drivegate_build_info", "gauge", "the running drivegate's version");
  w.sample("drivegate_build_info", "version=\"" + escape_label(view.version) + "\"", 1);
  w.family("process_start_time_seconds", "gauge", "start time of the process since the epoch");
  w.sample("process_start_time_seconds", "", view.started_unix);
  device_metrics(w, view);
  bus_metrics(w, view);
  listener_metrics(w, view);
  return w.str();
}

}  // namespace drivegate
