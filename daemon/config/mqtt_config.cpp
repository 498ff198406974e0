#include "mqtt_config.h"

#include <charconv>
#include <fstream>

#include "base/read_file.h"
#include "mqtt/sparkplug.h"
#include "net/key_file.h"
#include "server_config.h"

namespace drivegate {

namespace {

constexpr const char* kBrokerForm =
    "must be \"mqtt://host[:port]\" or \"mqtts://host[:port]\" (e.g. \"mqtt://10.1.2.3:1883\")";

// "mqtt://host[:port]" / "mqtts://host[:port]", IPv6 in brackets; false when it is not.
bool parse_broker(std::string_view url, MqttConfig& out) {
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

void read_tls_files(TableReader& r, MqttConfig& mqtt, Diagnostics& diag) {
  const auto ca = r.string("ca", false);
  const auto cert = r.string("cert", false);
  const auto key = r.string("key", false);
  if (!mqtt.tls) {
    if (ca || cert || key) {
      diag.error_at(mqtt.line, "mqtt", "ca, cert and key are for an mqtts:// broker");
    }
    return;
  }
  std::string error;
  if (!ca) {
    diag.error_at(mqtt.line, "mqtt.ca",
                  "an mqtts:// broker needs `ca`: the CA its certificate must chain to");
  } else {
    mqtt.ca = *ca;
    // libmosquitto reads it by path, at each connection, on the event loop: a FIFO would hang it.
    if (!is_readable_regular_file(mqtt.ca, error)) diag.error(r.node("ca"), "mqtt.ca", error);
  }
  if (cert.has_value() != key.has_value()) {
    diag.error_at(mqtt.line, "mqtt", "cert and key go together (a client certificate)");
    return;
  }
  if (cert) {
    mqtt.cert = *cert;
    mqtt.key = *key;
    if (!is_readable_regular_file(mqtt.cert, error)) {
      diag.error(r.node("cert"), "mqtt.cert", error);
    }
    if (!net::key_permissions_ok(mqtt.key, error) || !is_readable_regular_file(mqtt.key, error)) {
      diag.error(r.node("key"), "mqtt.key", error);
    }
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
  r.expect({"broker", "ca", "cert", "key", "client_id", "group_id", "edge_node_id",
            "primary_host_id", "username", "password_file", "deadband", "min_interval_ms",
            "counter_interval_ms", "keepalive_s", "commands", "access", "feed_failsafe"});
  MqttConfig& m = cfg.mqtt;
  m.enabled = true;
  m.line = line_of(*t);
  if (const auto broker = r.string("broker", true)) {
    m.broker = *broker;
    if (!parse_broker(*broker, m)) diag.error(r.node("broker"), "mqtt.broker", kBrokerForm);
  }
  read_tls_files(r, m, diag);
  read_id(r, "group_id", true, m.group_id, diag);
  read_id(r, "edge_node_id", true, m.edge_node_id, diag);
  read_id(r, "primary_host_id", false, m.primary_host_id, diag);
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
  if (m.feed_failsafe && !m.commands) {
    diag.warning_at(m.line, "mqtt.feed_failsafe", "has no effect while commands = false");
  }
  // Device names are Sparkplug device ids as they are: the configuration's name rule keeps '/',
  // '+' and '#' out of them (config_loader.cpp, check_name).
  if (m.commands && m.broker.starts_with("mqtt://")) {
    diag.warning_at(m.line, "mqtt.commands",
                    "commands over a plain mqtt:// broker: anyone who may publish there can move "
                    "the drives; use mqtts:// with broker ACLs (docs/mqtt.md)");
  }
}

}  // namespace drivegate
