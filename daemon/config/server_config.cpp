#include "server_config.h"

#include <algorithm>
#include <charconv>
#include <filesystem>

#include "config_loader.h"
#include "line_config.h"
#include "net/listen_host.h"

namespace drivegate {

std::optional<ListenAddress> parse_listen(std::string_view s) {
  std::string_view host;
  std::string_view port;
  if (s.starts_with("[")) {
    const auto close = s.find("]:");
    if (close == std::string_view::npos) return std::nullopt;
    host = s.substr(1, close - 1);
    port = s.substr(close + 2);
  } else {
    const auto colon = s.rfind(':');
    if (colon == std::string_view::npos) return std::nullopt;
    host = s.substr(0, colon);
    port = s.substr(colon + 1);
  }
  unsigned value = 0;
  const auto [p, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (ec != std::errc() || p != port.data() + port.size() || value > 65535 || port.empty()) {
    return std::nullopt;
  }
  return ListenAddress{host.empty() ? "0.0.0.0" : std::string(host),
                       static_cast<std::uint16_t>(value)};
}

namespace {

// A listener binds a numeric address: a name would need a DNS lookup at start-up, which can
// block, and can change under a running daemon.
bool bindable(const std::string& host) {
  return net::parse_listen_host(host).has_value();
}

bool wildcard(const std::string& host) {
  return host.empty() || host == "*" || host == "0.0.0.0" || host == "::";
}

constexpr const char* kListenForm = "must be \"host:port\" (e.g. \"0.0.0.0:502\" or \"[::]:802\")";

// The listener [server] listen declares (or the default one): what drivegate always served.
ListenerConfig server_listener(ListenAddress at, int line) {
  ListenerConfig l;
  l.host = std::move(at.host);
  l.port = at.port;
  l.policy.access = AccessLevel::maintain;
  l.from_server_listen = true;
  l.line = line;
  return l;
}

template <std::size_t N>
std::optional<std::size_t> index_of(const std::array<std::string_view, N>& names,
                                    std::string_view name) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  return static_cast<std::size_t>(it - names.begin());
}

std::string one_of(std::span<const std::string_view> names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    out += (i == 0 ? "\"" : (i + 1 == names.size() ? " or \"" : ", \"")) + std::string(names[i]) +
           "\"";
  }
  return out;
}

net::AllowList read_allow(const toml::node& n, const std::string& key, Diagnostics& diag) {
  net::AllowList allow;
  const auto* a = n.as_array();
  if (a == nullptr) {
    diag.error(&n, key, "must be an array of addresses or CIDR ranges, e.g. [\"10.1.2.0/24\"]");
    return allow;
  }
  if (a->empty()) {
    diag.error(&n, key, "is empty: nobody could connect (leave allow out to serve every address)");
  }
  for (const auto& item : *a) {
    const auto* s = item.as_string();
    std::string error = "must be a string";
    const auto range = s != nullptr ? net::parse_address_range(s->get(), error) : std::nullopt;
    if (range) {
      allow.push_back(*range);
    } else {
      diag.error(&item, key, error);
    }
  }
  return allow;
}

std::optional<ListenerTlsConfig> read_tls(const toml::node& n, const std::string& key,
                                          Diagnostics& diag) {
  const auto* t = n.as_table();
  if (t == nullptr) {
    diag.error(&n, key, "must be a table: { cert = \"...\", key = \"...\", ca = \"...\" }");
    return std::nullopt;
  }
  TableReader r(*t, key, diag);
  r.expect({"cert", "key", "ca"});
  ListenerTlsConfig tls;
  const auto cert = r.string("cert", true);
  const auto private_key = r.string("key", true);
  const auto ca = r.string("ca", true);
  if (!cert || !private_key || !ca) return std::nullopt;
  tls.cert = *cert;
  tls.key = *private_key;
  tls.ca = *ca;
  return tls;
}

TlsRoles read_roles(const toml::node& n, const std::string& key, Diagnostics& diag) {
  TlsRoles roles;
  const auto* t = n.as_table();
  if (t == nullptr) {
    diag.error(&n, key, "must be a table of role = access level, e.g. { operator = \"operate\" }");
    return roles;
  }
  for (const auto& [role, level] : *t) {
    const std::string where = key + "." + std::string(role.str());
    if (auto a = read_access(level, where, diag)) roles.emplace(std::string(role.str()), *a);
  }
  return roles;
}

// framing, and the keys only an RTU / ASCII listener has.
void read_framing(TableReader& r, ListenerConfig& l, Diagnostics& diag) {
  const bool serial = r.node("port") != nullptr;
  if (const auto* n = r.node("framing")) {
    const auto* s = n->as_string();
    const auto i = s != nullptr ? index_of(kListenerFramingNames, s->get()) : std::nullopt;
    if (!i) {
      diag.error(n, r.qualified("framing"), "must be " + one_of(kListenerFramingNames));
    } else {
      l.framing = static_cast<ListenerFraming>(*i);
      if (serial && l.framing == ListenerFraming::mbap) {
        diag.error(n, r.qualified("framing"),
                   "a serial line carries \"rtu\" or \"ascii\" frames (\"mbap\" is Modbus TCP's)");
      }
    }
  } else if (serial) {
    l.framing = ListenerFraming::rtu;
  }
  const bool slave = l.framing != ListenerFraming::mbap;
  for (const char* key : {"write_reply", "broadcast", "ascii_timeout_ms", "reply_timeout_ms"}) {
    if (!slave && r.node(key) != nullptr) {
      diag.error(r.node(key), r.qualified(key),
                 "only for a listener with framing = \"rtu\" or \"ascii\" (Modbus TCP answers "
                 "every write when the drive took it, and has no broadcast)");
    }
  }
  if (const auto* n = r.node("write_reply")) {
    const auto* s = n->as_string();
    const auto i = s != nullptr ? index_of(kWriteReplyNames, s->get()) : std::nullopt;
    if (i) {
      l.write_reply = static_cast<WriteReply>(*i);
    } else {
      diag.error(
          n, r.qualified("write_reply"),
          "must be " + one_of(kWriteReplyNames) +
              " (answer a write when the drive took it, or once it is validated and queued)");
    }
  }
  l.broadcast = r.boolean("broadcast").value_or(false);
  if (auto v = r.integer("reply_timeout_ms", 0, 60'000, false)) {
    l.reply_timeout = Millis(*v);
    if (*v > 0 && *v < kMinReplyTimeout.count()) {
      diag.error(r.node("reply_timeout_ms"), r.qualified("reply_timeout_ms"),
                 "0 (none) or at least " + std::to_string(kMinReplyTimeout.count()) +
                     " ms: no confirmed write could be answered sooner (a poll of its drive and "
                     "the line's own silences)");
    }
  }
  if (auto v = r.integer("ascii_timeout_ms", 10, 60'000, false)) {
    l.ascii_timeout = Millis(*v);
    if (l.framing != ListenerFraming::ascii || !serial) {
      diag.error(r.node("ascii_timeout_ms"), r.qualified("ascii_timeout_ms"),
                 "only for framing = \"ascii\" on a serial port (RTU frames end at 3.5 "
                 "characters of silence; on TCP a frame ends at its CR LF)");
    }
  }
  if (auto v = r.integer("rx_latency_ms", 0, 1000, false)) {
    l.rx_latency = Millis(*v);
    if (l.framing != ListenerFraming::rtu || !serial) {
      diag.error(r.node("rx_latency_ms"), r.qualified("rx_latency_ms"),
                 "only for framing = \"rtu\" on a serial port");
    }
  }
}

// The first line setting (a serial listener's) that a table gives, if any.
std::optional<std::string> first_line_key(TableReader& r) {
  for (const char* key : {"baud", "parity", "data_bits", "stop_bits", "rs485", "reopen_max_ms",
                          "echo", "network_delay_ms"}) {
    if (r.node(key) != nullptr) return std::string(key);
  }
  return std::nullopt;
}

// A serial listener: `port` and the line's settings, as a bus's (config/line_config.h). Modbus
// serial lines default to even parity (Serial Line 2.5.1), and ASCII to 7 data bits (2.5.2).
void read_serial(TableReader& r, const std::string& prefix, ListenerConfig& l, Diagnostics& diag) {
  if (r.node("address") != nullptr) {
    diag.error(r.node("address"), r.qualified("address"),
               "give address (a TCP listener) or port (a serial one), not both");
  }
  for (const char* key : {"allow", "max_clients", "tls", "roles", "tls_handshakes_per_s"}) {
    if (r.node(key) != nullptr) {
      diag.error(r.node(key), r.qualified(key),
                 "a serial listener has no network clients: whoever is on its line is its master");
    }
  }
  BusConfig line;
  line.parity = Parity::even;
  if (l.framing == ListenerFraming::ascii) line.data_bits = 7;
  read_line(r, prefix, line, diag);
  line.line = l.line;
  // A local port and RFC 2217 set the line; raw tcp:// leaves it to the device server, but its
  // character time is still what the frames are timed by.
  if (line.baud == 0) {
    diag.error(r.node("port"), r.qualified("baud"),
               "a serial listener needs its line's baud rate (its character times)");
  }
  if (l.framing == ListenerFraming::rtu && line.data_bits != 8) {
    diag.error(r.node("data_bits"), r.qualified("data_bits"),
               "RTU frames are 8 data bits (Serial Line 2.5.1)");
  }
  line.name = "listener " + line.port;
  l.port = 0;
  l.host = "";
  l.serial = std::move(line);
}

ListenerConfig read_listener(const toml::table& t, std::size_t index, Diagnostics& diag) {
  const std::string prefix = "listener[" + std::to_string(index) + "]";
  TableReader r(t, prefix, diag);
  r.expect({"address",
            "allow",
            "access",
            "word_order",
            "tls",
            "roles",
            "max_clients",
            "tls_handshakes_per_s",
            "framing",
            "write_reply",
            "broadcast",
            "ascii_timeout_ms",
            "reply_timeout_ms",
            "port",
            "baud",
            "parity",
            "data_bits",
            "stop_bits",
            "rs485",
            "reopen_max_ms",
            "echo",
            "rx_latency_ms"});
  ListenerConfig l;
  l.line = line_of(t);
  auto& policy = l.policy;
  policy.access = AccessLevel::read;  // nothing may write unless the file says so
  read_framing(r, l, diag);
  const bool serial = r.node("port") != nullptr;
  if (const auto line_key = first_line_key(r); line_key && !serial) {
    diag.error(r.node(*line_key), r.qualified(*line_key),
               "a line setting: only for a serial listener (port = \"/dev/...\")");
  }
  if (serial) {
    read_serial(r, prefix, l, diag);
  } else if (auto address = r.string("address", true)) {
    if (auto at = parse_listen(*address); at && !bindable(at->host)) {
      diag.error(r.node("address"), r.qualified("address"),
                 "\"" + at->host +
                     "\" is not a numeric IPv4 or IPv6 address (no name lookup: "
                     "give the address of the interface, or 0.0.0.0 / [::] for all)");
    } else if (at) {
      l.host = at->host;
      l.port = at->port;
    } else {
      diag.error(r.node("address"), r.qualified("address"),
                 std::string(kListenForm) + ", got \"" + *address + "\"");
    }
  }
  if (const auto* n = r.node("allow")) policy.allow = read_allow(*n, r.qualified("allow"), diag);
  if (auto v = r.integer("max_clients", 1, 1024, false)) {
    policy.max_clients = static_cast<std::size_t>(*v);
  }
  if (const auto* n = r.node("access")) {
    policy.access = read_access(*n, r.qualified("access"), diag).value_or(policy.access);
  }
  if (const auto* n = r.node("word_order")) {
    const auto* s = n->as_string();
    const auto i = s != nullptr ? index_of(kWordOrderNames, s->get()) : std::nullopt;
    if (i) {
      policy.word_order = static_cast<WordOrder>(*i);
    } else {
      diag.error(n, r.qualified("word_order"),
                 "must be " + one_of(kWordOrderNames) +
                     " (32-bit values: high word first, or low word first)");
    }
  }
  if (const auto* n = r.node("tls")) policy.tls = read_tls(*n, r.qualified("tls"), diag);
  if (auto v = r.integer("tls_handshakes_per_s", 0, 1000, false)) {
    if (!r.node("tls")) {
      diag.error(r.node("tls_handshakes_per_s"), r.qualified("tls_handshakes_per_s"),
                 "only a TLS listener does handshakes: add tls = { cert, key, ca }");
    }
    policy.handshakes = net::RateLimit::per_second_in_bursts_of_two(static_cast<unsigned>(*v));
  }
  if (l.framing != ListenerFraming::mbap && policy.tls) {
    diag.error(r.node("tls"), r.qualified("tls"),
               "Modbus/TCP Security carries Modbus TCP (MBAP) frames: a TLS listener's framing is "
               "\"mbap\"");
  }
  if (const auto* n = r.node("roles")) {
    auto roles = read_roles(*n, r.qualified("roles"), diag);
    if (!r.node("tls")) {
      diag.error(n, r.qualified("roles"),
                 "roles come from TLS client certificates: add tls = { cert, key, ca }");
    } else if (policy.tls) {
      policy.tls->roles = std::move(roles);
    }
  }
  return l;
}

// Whoever can reach this listener may write: worth a line in --check-config and the journal.
void warn_open_writes(const ListenerConfig& l, Diagnostics& diag) {
  if (l.serial) return;  // its line's master is whoever the wiring says
  const auto& p = l.policy;
  const bool can_write =
      p.access != AccessLevel::read ||
      (p.tls && std::any_of(p.tls->roles.begin(), p.tls->roles.end(),
                            [](const auto& role) { return role.second != AccessLevel::read; }));
  if (!can_write || !net::allows_everyone(p.allow)) return;
  const std::string where = l.from_server_listen ? "server.listen" : "listener";
  const std::string what =
      p.tls ? " lets every address with a certificate from its CA and a writing role write"
            : " lets every address that can reach it write (access " +
                  std::string(to_string(p.access)) + ")";
  diag.warning_at(
      l.line, where,
      listener_name(l) + what + "; give it an allow list, or access = \"read\" (docs/security.md)");
}

}  // namespace

std::optional<AccessLevel> read_access(const toml::node& n, const std::string& key,
                                       Diagnostics& diag) {
  const auto* s = n.as_string();
  const auto i = s != nullptr ? index_of(kAccessLevelNames, s->get()) : std::nullopt;
  if (!i) {
    diag.error(&n, key, "must be " + one_of(kAccessLevelNames));
    return std::nullopt;
  }
  return static_cast<AccessLevel>(*i);
}

void read_server(const toml::table& root, Config& cfg, Diagnostics& diag) {
  const toml::node* n = root.get("server");
  if (n == nullptr) return;
  const auto* t = n->as_table();
  if (t == nullptr) {
    diag.error(n, "server", "must be a table ([server])");
    return;
  }
  TableReader r(*t, "server", diag);
  r.expect({"listen", "max_clients", "idle_timeout_ms", "frame_timeout_ms"});
  if (auto listen = r.string("listen", false)) {
    if (auto at = parse_listen(*listen)) {
      cfg.listeners.push_back(server_listener(std::move(*at), line_of(*r.node("listen"))));
    } else {
      diag.error(r.node("listen"), "server.listen",
                 std::string(kListenForm) + ", got \"" + *listen + "\"");
    }
  }
  if (auto v = r.integer("max_clients", 1, 1024, false)) cfg.server.max_clients = *v;
  if (auto v = r.integer("idle_timeout_ms", 1000, 86'400'000, false)) {
    cfg.server.idle_timeout = Millis(*v);
  }
  if (auto v = r.integer("frame_timeout_ms", 10, 60'000, false)) {
    cfg.server.frame_timeout = Millis(*v);
  }
}

void read_listeners(const toml::table& root, Config& cfg, Diagnostics& diag) {
  const toml::array* tables = array_of_tables(root, "listener", diag);
  if (tables != nullptr && !cfg.listeners.empty()) {
    diag.error(root.get("listener"), "listener",
               "[server] listen and [[listener]] cannot both be given: declare that address as "
               "a [[listener]] too");
    return;
  }
  if (tables != nullptr) {
    for (std::size_t i = 0; i < tables->size(); ++i) {
      cfg.listeners.push_back(read_listener(*(*tables)[i].as_table(), i, diag));
    }
  }
  if (cfg.listeners.empty()) cfg.listeners.push_back(server_listener({"0.0.0.0", 502}, 0));
  for (std::size_t i = 0; i < cfg.listeners.size(); ++i) {
    const auto& a = cfg.listeners[i];
    for (std::size_t j = 0; j < i && !cfg.listeners[i].serial; ++j) {
      if (cfg.listeners[j].serial) continue;
      const auto& b = cfg.listeners[j];
      // Two listeners on one port clash when they name the same address, or when either is
      // every address ([::] is dual stack: it takes the IPv4 port too).
      if (a.port == b.port && a.port != 0 &&
          (a.host == b.host || wildcard(a.host) || wildcard(b.host))) {
        diag.error_at(cfg.listeners[i].line, "listener",
                      a.host + ":" + std::to_string(a.port) + " overlaps " + b.host + ":" +
                          std::to_string(b.port) + ", already the address of the listener on " +
                          "line " + std::to_string(cfg.listeners[j].line));
      }
    }
    warn_open_writes(cfg.listeners[i], diag);
  }
}

namespace {

// Whether two ports are one: local paths as the file system resolves them (/dev/serial/by-id/...
// is a symbolic link to /dev/ttyUSB0), device servers by what is written.
bool same_port(const std::string& a, const std::string& b) {
  if (a == b) return true;
  if (a.find("://") != std::string::npos || b.find("://") != std::string::npos) return false;
  std::error_code ea;
  std::error_code eb;
  const auto ca = std::filesystem::weakly_canonical(a, ea);
  const auto cb = std::filesystem::weakly_canonical(b, eb);
  return !ea && !eb && ca == cb;
}

}  // namespace

void check_serial_listeners(const Config& cfg, Diagnostics& diag) {
  for (std::size_t i = 0; i < cfg.listeners.size(); ++i) {
    const auto& l = cfg.listeners[i];
    if (!l.serial) continue;
    for (const auto& bus : cfg.buses) {
      if (same_port(bus.port, l.serial->port)) {
        diag.error_at(l.line, "listener",
                      "port " + l.serial->port + " is bus '" + bus.name + "''s (line " +
                          std::to_string(bus.line) +
                          "): a line is either drives' (polled by drivegate) or a master's");
      }
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (cfg.listeners[j].serial && same_port(cfg.listeners[j].serial->port, l.serial->port)) {
        diag.error_at(l.line, "listener",
                      "port " + l.serial->port + " is already the listener's on line " +
                          std::to_string(cfg.listeners[j].line));
      }
    }
  }
}

void read_history(const toml::table& root, Config& cfg, Diagnostics& diag) {
  const toml::node* n = root.get("history");
  if (n == nullptr) return;
  const auto* t = n->as_table();
  if (t == nullptr) {
    diag.error(n, "history", "must be a table ([history])");
    return;
  }
  TableReader r(*t, "history", diag);
  r.expect({"events", "commands", "refusals", "trend_seconds"});
  cfg.history.line = line_of(*t);
  if (auto v = r.integer("events", 0, 100'000, false)) {
    cfg.history.events = static_cast<std::size_t>(*v);
  }
  if (auto v = r.integer("commands", 0, 100'000, false)) {
    cfg.history.commands = static_cast<std::size_t>(*v);
  }
  if (auto v = r.integer("refusals", 0, 100'000, false)) {
    cfg.history.refusals = static_cast<std::size_t>(*v);
  }
  if (auto v = r.integer("trend_seconds", 0, 3600, false)) {
    cfg.history.trend_seconds = static_cast<std::size_t>(*v);
  }
}

void read_http(const toml::table& root, Config& cfg, Diagnostics& diag) {
  const toml::node* n = root.get("http");
  if (n == nullptr) return;
  const auto* t = n->as_table();
  if (t == nullptr) {
    diag.error(n, "http", "must be a table ([http])");
    return;
  }
  TableReader r(*t, "http", diag);
  r.expect({"listen", "allow", "capture", "requests_per_s"});
  cfg.http.enabled = true;
  cfg.http.line = line_of(*t);
  if (auto listen = r.string("listen", false)) {
    if (auto at = parse_listen(*listen); at && bindable(at->host)) {
      cfg.http.listen = *at;
    } else {
      diag.error(r.node("listen"), "http.listen",
                 std::string(kListenForm) + " with a numeric address, got \"" + *listen + "\"");
    }
  }
  if (const auto* a = r.node("allow")) cfg.http.allow = read_allow(*a, "http.allow", diag);
  cfg.http.capture = r.boolean("capture").value_or(false);
  if (auto v = r.integer("requests_per_s", 0, 1000, false)) {
    cfg.http.requests_per_s = static_cast<unsigned>(*v);
  }
  for (const auto& l : cfg.listeners) {
    if (l.serial) continue;
    if (l.port == cfg.http.listen.port && l.port != 0 &&
        (l.host == cfg.http.listen.host || wildcard(l.host) || wildcard(cfg.http.listen.host))) {
      diag.error(r.node("listen"), "http.listen",
                 "overlaps the Modbus listener on line " + std::to_string(l.line));
    }
  }
  if (net::allows_everyone(cfg.http.allow) && cfg.http.listen.host != "127.0.0.1" &&
      cfg.http.listen.host != "::1" && cfg.http.listen.host != "localhost") {
    diag.warning_at(cfg.http.line, "http",
                    "every address that can reach " + cfg.http.listen.host + ":" +
                        std::to_string(cfg.http.listen.port) +
                        " may read the status page and metrics" +
                        (cfg.http.capture ? " and capture the buses' traffic" : "") +
                        "; give it an allow list");
  }
}

}  // namespace drivegate
