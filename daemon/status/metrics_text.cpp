// Prometheus text exposition format 0.0.4: one HELP and one TYPE line per family, then its
// samples; counters end in _total; label values escape backslash, double quote and newline.
// Written straight into one string (the event loop waits while it is written): fmt for the
// numbers, each device's labels written once, no stream and no temporary string per sample.
//
// Named as Prometheus asks (https://prometheus.io/docs/practices/naming/): a measurement's name
// ends in its base unit (status/metric_units.h), and what is a name rather than a quantity (a
// fault, a command, an adapter's enumerated or bit-field point) is a label of a state set, one
// series per state, 1 for those in force, never a number to graph or average (OpenMetrics 1.0,
// https://github.com/prometheus/OpenMetrics/blob/v1.0.0/specification/OpenMetrics.md#stateset;
// 0.0.4 has no such type, so they are gauges). docs/metrics.md lists every family.
#include <fmt/compile.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <iterator>

#include "base/device_text.h"
#include "gateway/value_codec.h"
#include "status/metric_units.h"
#include "status/process_metrics.h"
#include "status/status_view.h"

namespace drivegate {

namespace {

// A typical document (six drives, one of each adapter) is about 105 KB: most of it the state
// sets, a line per state with the device's labels.
constexpr std::size_t kMetricsReserve = 128 * 1024;

void append_escaped(std::string& out, std::string_view v) {
  // The runs between the characters to escape are appended whole (nearly always: all of it).
  std::size_t run = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const char c = v[i];
    if (c != '\\' && c != '"' && c != '\n') continue;
    out.append(v.data() + run, i - run);
    out += c == '\n' ? std::string_view("\\n") : c == '"' ? std::string_view("\\\"") : "\\\\";
    run = i + 1;
  }
  out.append(v.data() + run, v.size() - run);
}

// The shortest digits that read back as the same double (fmt's default: 21.4, where printf's
// %.17g says 21.399999999999999). Counters and most gauges are whole numbers: those are written
// as integers, the same digits, without the float formatting's cost.
void append_number(std::string& out, double v) {
  if (std::isnan(v)) {
    out += "NaN";
  } else if (std::isinf(v)) {
    out += v > 0 ? "+Inf" : "-Inf";  // as the format spells them (a float point may say so)
  } else if (v == std::trunc(v) && std::fabs(v) < 1e15) {
    out += fmt::format_int(static_cast<long long>(v)).c_str();
    if (v == 0 && std::signbit(v)) out.insert(out.size() - 1, 1, '-');  // "-0", as it is
  } else {
    fmt::format_to(std::back_inserter(out), FMT_COMPILE("{}"), v);
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

// A device's labels and its points' values, read once per document.
struct DeviceRow {
  std::string labels;
  std::vector<PointValue> values;
  Device* device;
};

// `,name="value"`, escaped, appended to `out`.
void append_label(std::string& out, std::string_view name, std::string_view value) {
  out += ',';
  out += name;
  out += "=\"";
  append_escaped(out, value);
  out += '"';
}

// Whether a point's value is the one its label `l` names: for a bit field, bit l.value is set.
bool in_force(const PointSpec& spec, const Label& l, const Value& v) {
  std::int64_t n = 0;
  if (const auto* i = std::get_if<std::int64_t>(&v)) {
    n = *i;
  } else {
    const double d = number_of(v);  // a float point with names: only a whole number is one
    if (!std::isfinite(d) || d != std::trunc(d) || std::fabs(d) > 9.2e18) return false;
    n = static_cast<std::int64_t>(d);
  }
  if (!spec.bit_labels) return n == static_cast<std::int64_t>(l.value);
  return l.value < 64 && ((static_cast<std::uint64_t>(n) >> l.value) & 1U) != 0;
}

// One series per state of the point (its labels), each 1 when in force. Two labels of one name
// (a vendor table naming two codes alike) are one state, in force when either is: the same series
// twice would make Prometheus refuse the whole scrape.
void state_samples(Writer& w, std::string_view family, std::string_view labels, std::string& extra,
                   std::size_t prefix, std::string_view state_label, const PointSpec& spec,
                   const Value& v, bool skip_zero_bit = false) {
  const auto& all = spec.labels;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const Label& l = all[i];
    if (skip_zero_bit && spec.bit_labels && l.value == 0) continue;
    const auto same = [&](const Label& o) { return o.name == l.name; };
    if (std::any_of(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(i), same)) continue;
    bool on = false;
    for (std::size_t j = i; j < all.size() && !on; ++j) {
      on = same(all[j]) && in_force(spec, all[j], v);
    }
    extra.resize(prefix);
    append_label(extra, state_label, l.name);
    w.sample(family, labels, on ? 1 : 0, extra);
  }
}

// The HELP of a common row's state set (the rows' descriptions speak of registers).
std::string_view state_help(CommonLabels vocabulary) {
  switch (vocabulary) {
    case CommonLabels::status_bits:
      return "the status register's bits: 1 for each that is set";
    case CommonLabels::faults:
      return "the most severe active fault, unified (fault_code): 1 for the one in force";
    case CommonLabels::fault_bits:
      return "every active fault, unified (fault_mask): 1 for each";
    case CommonLabels::commands:
      return "the command in force: 1 for the one in force";
    case CommonLabels::none:
      break;
  }
  return "";
}

// The state label of a common row's state set: the word its vocabulary names.
std::string_view state_label(CommonLabels vocabulary) {
  switch (vocabulary) {
    case CommonLabels::status_bits:
      return "status";
    case CommonLabels::faults:
    case CommonLabels::fault_bits:
      return "fault";
    case CommonLabels::commands:
      return "command";
    case CommonLabels::none:
      break;
  }
  return "state";
}

// Every common point (gateway/common_block.h), from the rows of the register map: a number is a
// gauge (counters as _total), a named value or bit field a state set, the native fault a label.
void common_metrics(Writer& w, const std::vector<DeviceRow>& rows) {
  std::string name;
  std::string extra;
  for (std::size_t i = 0; i < rows.front().values.size(); ++i) {
    const MappedPoint* p = rows.front().values[i].first;
    if (!p->common() || p->source == PointSource::status_bit || per_bus(p->spec.name)) continue;
    const CommonRow* row = p->row();
    if (row == nullptr) continue;
    name = "drivegate_device_";
    if (row->labels != CommonLabels::none) {
      // status, fault_code, fault_mask, command. fault_mask's bit 0 is `none`, never set.
      name += p->spec.name;
      w.family(name, "gauge", state_help(row->labels));
      for (const DeviceRow& r : rows) {
        // Every device has the same common block, in the same order.
        extra.clear();
        state_samples(w, name, r.labels, extra, 0, state_label(row->labels), p->spec,
                      r.values.at(i).second, row->labels == CommonLabels::fault_bits);
      }
      continue;
    }
    if (p->spec.name == "native_fault") {
      // A code of the drive's own, with no names drivegate knows: a label, as the page shows it.
      name += "native_fault_info";
      w.family(name, "gauge", "the protocol's raw fault code or bits, in label native_fault");
      char code[16];
      for (const DeviceRow& r : rows) {
        const auto v = static_cast<std::uint32_t>(as_double(r.values.at(i).second));
        const auto end = fmt::format_to(code, FMT_COMPILE("0x{:04X}"), v);
        extra.clear();
        append_label(extra, "native_fault",
                     std::string_view(code, static_cast<std::size_t>(end - code)));
        w.sample(name, r.labels, 1, extra);
      }
      continue;
    }
    const bool age = p->spec.name == "data_age_ms";
    name += age ? std::string_view("data_age_seconds") : std::string_view(p->spec.name);
    if (row->counter) name += "_total";
    w.family(name, row->counter ? "counter" : "gauge",
             age ? "seconds since the last reply carrying the drive's state (NaN: never)"
                 : row->description);
    for (const DeviceRow& r : rows) {
      const Value& v = r.values.at(i).second;
      double x = number_of(v);                            // not known: NaN
      if (age) x = x >= 4294967295.0 ? NAN : x / 1000.0;  // never heard: NaN
      w.sample(name, r.labels, x);
    }
  }
}

// The adapters' own points: each with a unit drivegate_device_point_<base unit> (metric_units.h),
// each with named values drivegate_device_point_state, each bit field drivegate_device_point_flag,
// each string drivegate_device_point_info (its text a label); a number without a unit (a raw code,
// a counter of the protocol's) is left to the status JSON.
// Every family gathers every device's points, as the format wants a family's samples together.
void point_metrics(Writer& w, const std::vector<DeviceRow>& rows) {
  constexpr std::size_t kState = kBaseUnits.size();
  constexpr std::size_t kFlag = kState + 1;
  constexpr std::size_t kInfo = kState + 2;
  struct Sample {
    std::size_t family;
    std::size_t row;
    std::size_t value;
    MetricUnit unit;
  };
  std::vector<Sample> samples;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto& values = rows[r].values;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const PointSpec& spec = values[i].first->spec;
      if (values[i].first->common()) continue;
      if (spec.type == PointType::string) {
        // Its text, while it is known.
        if (std::holds_alternative<std::string>(values[i].second)) {
          samples.push_back({kInfo, r, i, {}});
        }
      } else if (!spec.labels.empty()) {
        samples.push_back({spec.bit_labels ? kFlag : kState, r, i, {}});
      } else if (const auto unit = metric_unit(spec.unit)) {
        samples.push_back({unit->base, r, i, *unit});
      }
    }
  }
  std::stable_sort(samples.begin(), samples.end(),
                   [](const Sample& a, const Sample& b) { return a.family < b.family; });
  std::string name;
  std::string help;
  std::string extra;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Sample& s = samples[k];
    const DeviceRow& row = rows[s.row];
    const auto& [point, value] = row.values[s.value];
    if (k == 0 || samples[k - 1].family != s.family) {
      name = "drivegate_device_point_";
      if (s.family == kInfo) {
        name += "info";
        help =
            "adapter points that are text (a serial number, a drive's name): 1, the text in "
            "label value (printable ASCII, other bytes '?', at most 64 characters)";
      } else if (s.family == kState) {
        name += "state";
        help = "adapter points with named values: 1 for the name of the value in force";
      } else if (s.family == kFlag) {
        name += "flag";
        help = "adapter points that are bit fields: 1 for each named bit that is set";
      } else {
        name += s.unit.unit().suffix;
        help = "adapter points measured in ";
        help += s.unit.unit().words;
        help += ", converted from the point's unit (docs/metrics.md)";
      }
      w.family(name, "gauge", help);
    }
    extra.clear();
    append_label(extra, "point", point->spec.name);
    if (s.family == kInfo) {
      std::string text;
      append_device_text(text, std::get<std::string>(value), kMaxLabelText);
      append_label(extra, "value", text);
      w.sample(name, row.labels, 1, extra);
      continue;
    }
    if (s.family == kState || s.family == kFlag) {
      state_samples(w, name, row.labels, extra, extra.size(), s.family == kState ? "state" : "flag",
                    point->spec, value);
      continue;
    }
    // A float carries about 7 significant digits, a register times its scale at most 12, a
    // 64-bit value up to 17 (what a double holds).
    const PointType type = point->spec.type;
    const bool wide = type == PointType::u64 || type == PointType::i64 || type == PointType::f64;
    const int digits = type == PointType::f32 ? 7 : wide ? 17 : 12;
    w.sample(name, row.labels, round_significant(s.unit.to_base(number_of(value)), digits), extra);
  }
}

void device_metrics(Writer& w, const StatusView& view) {
  std::vector<DeviceRow> rows;
  rows.reserve(view.gateway.devices().size());
  for (const auto& d : view.gateway.devices()) {
    DeviceRow& r = rows.emplace_back(DeviceRow{device_labels(*d), {}, d.get()});
    point_values(*d, Clock::now(), r.values);
  }
  w.family("drivegate_device_online", "gauge",
           "1 when the drive answers and its protocol is up (status bit online)");
  for (const DeviceRow& r : rows) w.sample("drivegate_device_online", r.labels, r.device->online());
  w.family("drivegate_device_comm_lost", "gauge", "1 when the drive stopped answering");
  for (const DeviceRow& r : rows) {
    w.sample("drivegate_device_comm_lost", r.labels, r.device->comm_lost());
  }
  w.family("drivegate_device_failsafe_latched", "gauge",
           "1 while the PLC-loss failsafe holds the drive stopped");
  for (const DeviceRow& r : rows) {
    w.sample("drivegate_device_failsafe_latched", r.labels, r.device->failsafe_latched());
  }
  // The write queue (docs/safety.md, "Fair line time") and late replies.
  const auto each = [&](std::string_view family, std::string_view type, std::string_view help,
                        auto f) {
    w.family(family, type, help);
    for (const DeviceRow& r : rows) w.sample(family, r.labels, static_cast<double>(f(*r.device)));
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
  if (rows.empty()) return;
  common_metrics(w, rows);
  point_metrics(w, rows);
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

// The RTU / ASCII listeners on serial lines (docs/serial-listeners.md), when there are any.
void serial_metrics(Writer& w, const StatusView& view) {
  if (view.serial.empty()) return;
  std::vector<std::string> labels;
  labels.reserve(view.serial.size());
  for (const auto& l : view.serial) {
    std::string& label = labels.emplace_back("port=\"");
    append_escaped(label, l.port);
    label += '"';
  }
  const auto family = [&](std::string_view name, std::string_view type, std::string_view help,
                          auto f) {
    w.family(name, type, help);
    for (std::size_t i = 0; i < view.serial.size(); ++i) {
      w.sample(name, labels[i], static_cast<double>(f(view.serial[i])));
    }
  };
  using L = SerialListenerView;
  family("drivegate_serial_listener_open", "gauge", "1 while the listener's port is open",
         [](const L& l) { return l.open ? 1 : 0; });
  family("drivegate_serial_listener_reopens_total", "counter", "times the port was lost",
         [](const L& l) { return l.reopens; });
  family("drivegate_serial_listener_received_bytes_total", "counter", "bytes the line carried in",
         [](const L& l) { return l.bytes_received; });
  family("drivegate_serial_listener_frames_total", "counter",
         "frames seen on the line, any address, CRC good or not (FC 08 0x0B)",
         [](const L& l) { return l.counters.bus_messages; });
  family("drivegate_serial_listener_crc_errors_total", "counter",
         "frames whose CRC or LRC did not check (FC 08 0x0C)",
         [](const L& l) { return l.counters.bus_comm_errors; });
  family("drivegate_serial_listener_requests_total", "counter",
         "requests for our units or broadcast, processed (FC 08 0x0E)",
         [](const L& l) { return l.counters.server_messages; });
  family("drivegate_serial_listener_exceptions_total", "counter",
         "exception responses sent (FC 08 0x0D)",
         [](const L& l) { return l.counters.bus_exception_errors; });
  family("drivegate_serial_listener_not_answered_total", "counter",
         "requests for us not answered: broadcasts, and replies the master gave up on (FC 08 0x0F)",
         [](const L& l) { return l.counters.server_no_response; });
  family("drivegate_serial_listener_broken_frames_total", "counter",
         "frames cut by a gap, and noise: discarded",
         [](const L& l) { return l.counters.broken_frames; });
  family("drivegate_serial_listener_overruns_total", "counter",
         "runs longer than the longest frame (FC 08 0x12)",
         [](const L& l) { return l.counters.bus_char_overruns; });
  family("drivegate_serial_listener_other_units_total", "counter",
         "good requests for a unit nobody here serves (other slaves on the line)",
         [](const L& l) { return l.counters.other_units; });
  family("drivegate_serial_listener_broadcasts_total", "counter", "requests to address 0",
         [](const L& l) { return l.counters.broadcasts; });
  family("drivegate_serial_listener_broadcasts_refused_total", "counter",
         "broadcast writes not applied (broadcast = false)",
         [](const L& l) { return l.counters.broadcasts_refused; });
  family("drivegate_serial_listener_busy_total", "counter",
         "exception 06 replies: the drive's write queue full (FC 08 0x11)",
         [](const L& l) { return l.counters.server_busy; });
  family("drivegate_serial_listener_accepted_then_failed_total", "counter",
         "writes answered as accepted (write_reply) that the drive then did not take",
         [](const L& l) { return l.counters.write_timeouts; });
}

// The Sparkplug B northbound ([mqtt], docs/mqtt.md).
void mqtt_metrics(Writer& w, const mqtt::NorthboundStatus& m) {
  w.single("drivegate_mqtt_connected", "gauge", "1 while the session with the broker is up",
           m.connected ? 1 : 0);
  w.single("drivegate_mqtt_online", "gauge",
           "1 once the births are out (and the primary host, if any, is online)",
           m.session == "online" ? 1 : 0);
  w.single("drivegate_mqtt_bdseq", "gauge", "the session's Sparkplug bdSeq", m.bd_seq);
  w.single("drivegate_mqtt_broker_index", "gauge",
           "which of [mqtt] brokers is in use, from 0 (the URL: /api/v1/status)",
           static_cast<double>(m.broker_index));
  w.single("drivegate_mqtt_broker_switches_total", "counter",
           "moves to the next of [mqtt] brokers after a failure or an offline primary host",
           static_cast<double>(m.broker_switches));
  w.single("drivegate_mqtt_connects_total", "counter", "sessions begun with the broker",
           static_cast<double>(m.connects));
  w.single("drivegate_mqtt_connection_losses_total", "counter",
           "connection attempts that failed and sessions lost", static_cast<double>(m.losses));
  w.single("drivegate_mqtt_sessions_lost_total", "counter",
           "sessions that were up and ended without being ended here (one per outage)",
           static_cast<double>(m.sessions_lost));
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
  if (!m.store.enabled) return;
  const mqtt::StoreStats& st = m.store;
  const auto count = [](std::uint64_t n) { return static_cast<double>(n); };
  w.single("drivegate_mqtt_store_records", "gauge",
           "changes kept on disk while there was no session, not yet sent", count(st.records));
  w.single("drivegate_mqtt_store_bytes", "gauge", "the store's size on disk", count(st.bytes));
  w.single("drivegate_mqtt_store_oldest_timestamp_seconds", "gauge",
           "when the oldest change waiting was kept (Unix time; 0: none waits)",
           st.oldest_ms ? static_cast<double>(*st.oldest_ms) / 1000.0 : 0.0);
  w.single("drivegate_mqtt_store_kept_total", "counter", "changes kept for later", count(st.kept));
  w.single("drivegate_mqtt_store_replayed_total", "counter",
           "kept changes sent as historical DDATA", count(st.replayed));
  w.single("drivegate_mqtt_store_dropped_total", "counter",
           "kept changes never sent: beyond store_max_mb (oldest first) or store_max_age_h, for "
           "a device not born in the session, or lost with a file of the store",
           count(st.dropped_size + st.dropped_age + st.replay_dropped + st.dropped_lost));
  w.single("drivegate_mqtt_store_refused_total", "counter",
           "changes the disk refused to keep (see the journal)", count(st.refused));
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

// Every write by who asked and what came of it (history/command_audit.h): every pair, those
// that never happened as 0, so that a rate or an alert on one has a series from the start.
void write_metrics(Writer& w, const CommandCounts& counts) {
  const auto by_source_and_result = [&](std::string_view name, auto value) {
    std::string labels;
    for (std::size_t s = 0; s < kSourceKindNames.size(); ++s) {
      for (std::size_t o = 0; o < kOutcomeNames.size(); ++o) {
        labels = "source=\"";
        labels += kSourceKindNames[s];
        labels += "\",result=\"";
        labels += result_name(static_cast<Outcome>(o));  // as the journal's RESULT= says it
        labels += '"';
        w.sample(name, labels,
                 static_cast<double>(value(static_cast<SourceKind>(s), static_cast<Outcome>(o))));
      }
    }
  };
  w.family("drivegate_writes_total", "counter",
           "writes to the drives, from any northbound or the gateway itself, by source and result");
  by_source_and_result("drivegate_writes_total",
                       [&](SourceKind s, Outcome o) { return counts.at(s, o); });
  w.family("drivegate_audit_folded_total", "counter",
           "of those, writes not recorded one by one but folded into a summary record, "
           "by source and result");
  by_source_and_result("drivegate_audit_folded_total",
                       [&](SourceKind s, Outcome o) { return counts.folded(s, o); });
}

// The event history (history/event_log.h): how full it is, and what it had to let go.
void history_metrics(Writer& w, const EventLog& log) {
  w.single("drivegate_history_events", "gauge", "entries the event history holds now",
           static_cast<double>(log.size()));
  w.single("drivegate_history_dropped_total", "counter",
           "history entries pushed out, oldest first, to make room for newer ones",
           static_cast<double>(log.dropped()));
  w.single("drivegate_history_bytes", "gauge", "memory the event history's entries take",
           static_cast<double>(log.memory_bytes()));
  const auto by_shelf = [&](std::string_view name, std::string_view type, std::string_view help,
                            auto value) {
    w.family(name, type, help);
    std::string labels;
    for (std::size_t i = 0; i < kShelfNames.size(); ++i) {
      labels = "shelf=\"";
      labels += kShelfNames[i];
      labels += '"';
      w.sample(name, labels, static_cast<double>(value(static_cast<Shelf>(i))));
    }
  };
  by_shelf("drivegate_history_shelf_entries", "gauge",
           "entries each shelf of the event history holds now",
           [&](Shelf s) { return log.size(s); });
  by_shelf("drivegate_history_shelf_capacity", "gauge",
           "entries each shelf of the event history keeps at most ([history])",
           [&](Shelf s) { return log.capacity(s); });
  by_shelf("drivegate_history_shelf_dropped_total", "counter",
           "entries each shelf of the event history pushed out, oldest first",
           [&](Shelf s) { return log.dropped(s); });
}

// The standard process metrics (status/process_metrics.h); one whose file could not be read is
// left out, but the start time falls back to the daemon's own clock.
void process_families(Writer& w, const ProcessMetrics& m, double started_unix) {
  if (m.cpu_seconds) {
    w.single("process_cpu_seconds_total", "counter", "user and system CPU time spent, seconds",
             *m.cpu_seconds);
  }
  if (m.open_fds) {
    w.single("process_open_fds", "gauge", "open file descriptors", *m.open_fds);
  }
  if (m.max_fds) {
    w.single("process_max_fds", "gauge", "the limit on open file descriptors (RLIMIT_NOFILE)",
             *m.max_fds);
  }
  if (m.virtual_memory_bytes) {
    w.single("process_virtual_memory_bytes", "gauge", "virtual memory size, bytes",
             *m.virtual_memory_bytes);
  }
  if (m.resident_memory_bytes) {
    w.single("process_resident_memory_bytes", "gauge", "resident memory size, bytes",
             *m.resident_memory_bytes);
  }
  w.single("process_start_time_seconds", "gauge", "start time of the process since the epoch",
           m.start_time_seconds.value_or(started_unix));
}

}  // namespace

void metrics_text(const StatusView& view, std::string& out) {
  Writer w(out);
  w.family("drivegate_build_info", "gauge", "the running drivegate's version");
  std::string version = "version=\"";
  append_escaped(version, view.version);
  version += '"';
  w.sample("drivegate_build_info", version, 1);
  process_families(w, read_process_metrics(), view.started_unix);
  w.single("drivegate_restart_needed", "gauge",
           "1 while the configuration file asks for what only a restart applies",
           view.restart_needed != nullptr && !view.restart_needed->empty() ? 1 : 0);
  device_metrics(w, view);
  if (view.commands != nullptr) write_metrics(w, *view.commands);
  if (view.history != nullptr) history_metrics(w, *view.history);
  bus_metrics(w, view);
  listener_metrics(w, view);
  serial_metrics(w, view);
  if (view.mqtt != nullptr) mqtt_metrics(w, *view.mqtt);
  if (view.http) http_metrics(w, *view.http, view.http_clients);
}

std::string metrics_text(const StatusView& view) {
  std::string out;
  out.reserve(kMetricsReserve);
  metrics_text(view, out);
  return out;
}

}  // namespace drivegate
