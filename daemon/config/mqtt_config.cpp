#include "mqtt_config.h"

#include <algorithm>
#include <charconv>
#include <fstream>
#include <optional>

#include "base/read_file.h"
#include "mqtt/sparkplug.h"
#include "net/key_file.h"
#include "server_config.h"

namespace drivegate {

namespace {

constexpr const char* kBrokerForm =
    "must be \"mqtt://host[:port]\" or \"mqtts://host[:port]\" (e.g. \"mqtt://10.1.2.3:1883\")";

// "mqtt://host[:port]" / "mqtts://host[:port]", IPv6 in brackets; false when it is not.
bool parse_broker(std::string_view url, MqttBroker& out) {
  std::string_view rest;
  if (url.starts_with("mqtt://")) {
    rest = url.substr(7);
    out.tls = false;
    out.port = 1883;  // IANA "mqtt"
  } else if (url.starts_with("mqtts://")) {
    rest = url.substr(8);
    out.tls = true;
    out.port = 8883;  // IANA "secure-mqtt"
  } else {
    return false;
  }
  std::string_view host = rest;
  std::string_view port;
  if (rest.starts_with("[")) {
    const auto close = rest.find(']');
    if (close == std::string_view::npos) return false;
    host = rest.substr(1, close - 1);
    const auto after = rest.substr(close + 1);
    if (!after.empty()) {
      if (!after.starts_with(":")) return false;
      port = after.substr(1);
    }
  } else if (const auto colon = rest.rfind(':'); colon != std::string_view::npos) {
    host = rest.substr(0, colon);
    port = rest.substr(colon + 1);
  }
  if (host.empty() || host.find_first_of("/?# ") != std::string_view::npos) return false;
  if (!port.empty() || rest.ends_with(":")) {
    unsigned value = 0;
    const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
    if (ec != std::errc() || end != port.data() + port.size() || value == 0 || value > 65535) {
      return false;
    }
    out.port = static_cast<std::uint16_t>(value);
  }
  out.host = std::string(host);
  return true;
}

void read_id(TableReader& r, std::string_view key, bool required, std::string& out,
             Diagnostics& diag) {
  const auto v = r.string(key, required);
  if (!v) return;
  if (!sparkplug::valid_id(*v)) {
    diag.error(r.node(key), r.qualified(key),
               "must be a Sparkplug id: not empty, without '/', '+' or '#'");
    return;
  }
  out = *v;
}

void read_deadband(const toml::node& n, const std::string& key, MqttConfig& mqtt,
                   Diagnostics& diag) {
  const auto* t = n.as_table();
  if (t == nullptr) {
    diag.error(&n, key, "must be a table of point name = amount, e.g. { speed_rpm = 5 }");
    return;
  }
  for (const auto& [name, value] : *t) {
    const auto amount = value.value<double>();
    if (!amount || *amount < 0.0) {
      diag.error(&value, key + "." + std::string(name.str()), "must be a number >= 0");
      continue;
    }
    mqtt.deadband.emplace_back(std::string(name.str()), *amount);
  }
}

void read_password(const std::filesystem::path& file, const toml::node* at, MqttConfig& mqtt,
                   Diagnostics& diag) {
  std::string error;
  if (!net::key_permissions_ok(file, error)) {
    diag.error(at, "mqtt.password_file", error);
    return;
  }
  const auto text = read_regular_file(file, 64 * 1024, error);
  if (!text) {
    diag.error(at, "mqtt.password_file", error);
    return;
  }
  mqtt.password = text->substr(0, text->find_first_of("\r\n"));
}

// ca, cert and key as one table has them ([mqtt]'s, the defaults; or one broker's), each file
// checked where it is written.
struct TlsFiles {
  std::optional<std::filesystem::path> ca;
  std::optional<std::filesystem::path> cert;
  std::optional<std::filesystem::path> key;
  [[nodiscard]] bool any() const { return ca || cert || key; }
};

TlsFiles read_tls_files(TableReader& r, Diagnostics& diag) {
  TlsFiles f;
  std::string error;
  if (const auto ca = r.string("ca", false)) {
    f.ca = *ca;
    // libmosquitto reads it by path, at each connection, on the event loop: a FIFO would hang it.
    if (!is_readable_regular_file(*f.ca, error)) diag.error(r.node("ca"), r.qualified("ca"), error);
  }
  const auto cert = r.string("cert", false);
  const auto key = r.string("key", false);
  if (cert.has_value() != key.has_value()) {
    diag.error(r.node(cert ? "cert" : "key"), r.qualified(cert ? "cert" : "key"),
               "cert and key go together (a client certificate)");
    return f;
  }
  if (cert) {
    f.cert = *cert;
    f.key = *key;
    if (!is_readable_regular_file(*f.cert, error)) {
      diag.error(r.node("cert"), r.qualified("cert"), error);
    }
    if (!net::key_permissions_ok(*f.key, error) || !is_readable_regular_file(*f.key, error)) {
      diag.error(r.node("key"), r.qualified("key"), error);
    }
  }
  return f;
}

// One broker: its URL and, for mqtts://, its TLS files (its own, else [mqtt]'s). `at` is where it
// is written, `key` its name in messages ("mqtt.broker", "mqtt.brokers[1]").
std::optional<MqttBroker> make_broker(const std::string& url, const TlsFiles& own,
                                      const TlsFiles& shared, const toml::node* at,
                                      const std::string& key, Diagnostics& diag) {
  MqttBroker b;
  // mqtt://user:password@host: the URL is shown in the status and the log, and the password with
  // it. The message does not quote it either.
  if (const auto scheme = url.find("://");
      scheme != std::string::npos && url.find('@', scheme) != std::string::npos) {
    diag.error(at, key,
               "credentials in a broker URL are not supported (the URL is shown in the status "
               "and the log): give them as username and password_file");
    return std::nullopt;
  }
  b.url = url;
  if (!parse_broker(url, b)) {
    diag.error(at, key, kBrokerForm);
    return std::nullopt;
  }
  if (!b.tls) {
    if (own.any()) diag.error(at, key, "ca, cert and key are for an mqtts:// broker");
    return b;
  }
  const TlsFiles& files = own.ca ? own : shared;  // a broker's own CA brings its own client pair
  if (!files.ca) {
    diag.error(at, key + (own.any() ? ".ca" : ""),
               "an mqtts:// broker needs `ca`: the CA its certificate must chain to (mqtt.ca)");
    return std::nullopt;
  }
  b.ca = *files.ca;
  const TlsFiles& pair = own.cert ? own : files;
  if (pair.cert) {
    b.cert = *pair.cert;
    b.key = *pair.key;
  }
  return b;
}

// `broker = "..."` or `brokers = ["...", { url = "...", ca = "..." }, ...]`.
void read_brokers(TableReader& r, MqttConfig& m, Diagnostics& diag) {
  const TlsFiles shared = read_tls_files(r, diag);
  const toml::node* one = r.node("broker");
  const toml::node* many = r.node("brokers");
  if ((one == nullptr) == (many == nullptr)) {
    diag.error_at(m.line, "mqtt.broker",
                  one == nullptr ? "required key is missing (or `brokers`, a list of them)"
                                 : "broker or brokers, not both");
    return;
  }
  if (one != nullptr) {
    if (const auto url = r.string("broker", true)) {
      if (auto b = make_broker(*url, {}, shared, one, "mqtt.broker", diag)) {
        m.brokers.push_back(std::move(*b));
      }
    }
  } else {
    const auto* list = many->as_array();
    if (list == nullptr || list->empty() || list->size() > kMaxBrokers) {
      diag.error(many, "mqtt.brokers",
                 "must be a list of 1.." + std::to_string(kMaxBrokers) +
                     " brokers, each \"mqtt[s]://host[:port]\" or { url = \"...\", ca = ..., "
                     "cert = ..., key = ... }");
      return;
    }
    for (std::size_t i = 0; i < list->size(); ++i) {
      const toml::node& item = *list->get(i);
      const std::string key = "mqtt.brokers[" + std::to_string(i) + "]";
      std::optional<MqttBroker> b;
      if (const auto* text = item.as_string()) {
        b = make_broker(text->get(), {}, shared, &item, key, diag);
      } else if (const auto* t = item.as_table()) {
        TableReader br(*t, key, diag);
        br.expect({"url", "ca", "cert", "key"});
        const TlsFiles own = read_tls_files(br, diag);
        if (const auto url = br.string("url", true)) {
          b = make_broker(*url, own, shared, &item, key, diag);
        }
      } else {
        diag.error(&item, key, "must be a broker URL or a table { url = \"...\", ... }");
      }
      if (b) m.brokers.push_back(std::move(*b));
    }
  }
  const bool any_tls =
      std::any_of(m.brokers.begin(), m.brokers.end(), [](const MqttBroker& b) { return b.tls; });
  if (shared.any() && !any_tls && !m.brokers.empty()) {
    diag.error_at(m.line, "mqtt", "ca, cert and key are for an mqtts:// broker");
  }
}

}  // namespace

void read_mqtt(const toml::table& root, Config& cfg, Diagnostics& diag) {
  const toml::node* n = root.get("mqtt");
  if (n == nullptr) return;
  const auto* t = n->as_table();
  if (t == nullptr) {
    diag.error(n, "mqtt", "must be a table ([mqtt])");
    return;
  }
  TableReader r(*t, "mqtt", diag);
  r.expect({"broker",
            "brokers",
            "ca",
            "cert",
            "key",
            "client_id",
            "group_id",
            "edge_node_id",
            "primary_host_id",
            "username",
            "password_file",
            "deadband",
            "min_interval_ms",
            "counter_interval_ms",
            "keepalive_s",
            "commands",
            "access",
            "feed_failsafe",
            "primary_host_version",
            "store_forward",
            "store_max_mb",
            "store_max_age_h",
            "replay_per_s"});
  MqttConfig& m = cfg.mqtt;
  m.enabled = true;
  m.line = line_of(*t);
  read_brokers(r, m, diag);
  read_id(r, "group_id", true, m.group_id, diag);
  read_id(r, "edge_node_id", true, m.edge_node_id, diag);
  read_id(r, "primary_host_id", false, m.primary_host_id, diag);
  if (const auto v = r.string("primary_host_version", false)) {
    // Which STATE the primary host publishes: 3.0's JSON (the default) or 2.2's text.
    if (*v == "2.2") {
      m.primary_host_state = MqttHostState::v2_2;
    } else if (*v != "3.0") {
      diag.error(r.node("primary_host_version"), "mqtt.primary_host_version",
                 "must be \"3.0\" (spBv1.0/STATE/<id>, JSON) or \"2.2\" (STATE/<id>, ONLINE / "
                 "OFFLINE), not \"" +
                     *v + "\"");
    }
    if (m.primary_host_id.empty()) {
      diag.warning_at(m.line, "mqtt.primary_host_version", "has no effect without primary_host_id");
    }
  }
  if (const auto id = r.string("client_id", false)) {
    if (id->empty() || id->size() > 65535) {
      diag.error(r.node("client_id"), "mqtt.client_id", "must be 1..65535 characters");
    }
    m.client_id = *id;
  } else {
    m.client_id = "drivegate-" + m.edge_node_id;
  }
  m.username = r.string("username", false).value_or("");
  if (const auto file = r.string("password_file", false)) {
    m.password_file = *file;
    if (m.username.empty()) {
      diag.error(r.node("password_file"), "mqtt.password_file", "needs a username");
    } else {
      read_password(m.password_file, r.node("password_file"), m, diag);
    }
  }
  if (const auto* d = r.node("deadband")) read_deadband(*d, "mqtt.deadband", m, diag);
  m.min_interval = Millis(r.integer("min_interval_ms", 0, 3'600'000, false).value_or(100));
  m.counter_interval =
      Millis(r.integer("counter_interval_ms", 0, 86'400'000, false).value_or(10'000));
  m.keepalive = std::chrono::seconds(r.integer("keepalive_s", 5, 3600, false).value_or(30));
  m.commands = r.boolean("commands").value_or(false);
  if (const auto* a = r.node("access")) {
    m.access = read_access(*a, "mqtt.access", diag).value_or(m.access);
  }
  m.feed_failsafe = r.boolean("feed_failsafe").value_or(false);
  m.store_forward = r.boolean("store_forward").value_or(true);
  m.store_max_bytes =
      static_cast<std::uint64_t>(r.integer("store_max_mb", 1, 65536, false).value_or(64)) * 1024 *
      1024;
  m.store_max_age =
      std::chrono::hours(r.integer("store_max_age_h", 1, 24 * 90, false).value_or(24));
  m.replay_per_s =
      static_cast<unsigned>(r.integer("replay_per_s", 10, 100'000, false).value_or(500));
  if (m.feed_failsafe && !m.commands) {
    diag.warning_at(m.line, "mqtt.feed_failsafe", "has no effect while commands = false");
  }
  // Device names are Sparkplug device ids as they are: the configuration's name rule keeps '/',
  // '+' and '#' out of them (config_loader.cpp, check_name).
  const bool plain =
      std::any_of(m.brokers.begin(), m.brokers.end(), [](const MqttBroker& b) { return !b.tls; });
  if (m.commands && plain) {
    diag.warning_at(m.line, "mqtt.commands",
                    "commands over a plain mqtt:// broker: anyone who may publish there can move "
                    "the drives; use mqtts:// with broker ACLs (docs/mqtt.md)");
  }
}

}  // namespace drivegate
