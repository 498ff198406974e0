#include "config/config_diff.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

namespace drivegate {

namespace {

std::string text(const OptionValue& v) {
  return std::visit(
      [](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, std::vector<std::string>>) {
          return fmt::format("[{}]", fmt::join(x, ", "));
        } else {
          return fmt::format("{}", x);
        }
      },
      v);
}

// Appends "key old -> new" when the two differ.
template <class T>
void note(std::vector<std::string>& out, std::string_view key, const T& a, const T& b) {
  if (a != b) out.push_back(fmt::format("{} {} -> {}", key, a, b));
}

template <class Named>
const Named* by_name(const std::vector<Named>& list, const std::string& name) {
  const auto it =
      std::find_if(list.begin(), list.end(), [&](const Named& x) { return x.name == name; });
  return it != list.end() ? &*it : nullptr;
}

}  // namespace

bool same_settings(const BusConfig& a, const BusConfig& b) {
  return changes(a, b).empty();
}

bool same_settings(const DeviceConfig& a, const DeviceConfig& b) {
  return changes(a, b).empty();
}

std::vector<std::string> changes(const BusConfig& a, const BusConfig& b) {
  std::vector<std::string> out;
  note(out, "port", a.port, b.port);
  note(out, "baud", a.baud, b.baud);
  note(out, "parity", to_string(a.parity), to_string(b.parity));
  note(out, "data_bits", int{a.data_bits}, int{b.data_bits});
  note(out, "stop_bits", int{a.stop_bits}, int{b.stop_bits});
  note(out, "echo", a.echo, b.echo);
  note(out, "rs485", a.rs485, b.rs485);
  note(out, "reopen_max_ms", a.reopen_max.count(), b.reopen_max.count());
  note(out, "network_delay_ms", a.network_delay.count(), b.network_delay.count());
  return out;
}

std::vector<std::string> changes(const DeviceConfig& a, const DeviceConfig& b) {
  std::vector<std::string> out;
  note(out, "bus", a.bus, b.bus);
  note(out, "adapter", a.adapter, b.adapter);
  note(out, "unit_id", int{a.unit_id}, int{b.unit_id});
  note(out, "address", a.address, b.address);
  note(out, "poll_ms", a.poll_interval.count(), b.poll_interval.count());
  note(out, "budget_ms", a.budget.count(), b.budget.count());
  note(out, "backoff_max_ms", a.backoff_max.count(), b.backoff_max.count());
  note(out, "failsafe_timeout_ms", a.failsafe.timeout.count(), b.failsafe.timeout.count());
  note(out, "failsafe_action", to_string(a.failsafe.action), to_string(b.failsafe.action));
  note(out, "failsafe_rpm", a.failsafe.preset_rpm, b.failsafe.preset_rpm);
  note(out, "on_shutdown",
       std::string_view(a.on_shutdown == ShutdownAction::stop ? "stop" : "hold"),
       std::string_view(b.on_shutdown == ShutdownAction::stop ? "stop" : "hold"));
  note(out, "on_start", std::string_view(a.on_start == StartAction::adopt ? "adopt" : "stop"),
       std::string_view(b.on_start == StartAction::adopt ? "adopt" : "stop"));
  // What the adapter read (a profile): the file, and its content.
  if (a.files_read != b.files_read) {
    const auto read = [](const std::string& f) { return f.empty() ? "(no file)" : f; };
    out.push_back(fmt::format("{} -> {}", read(a.files_read), read(b.files_read)));
  }
  // Options, by name: those in either (a changed adapter has other names altogether).
  const auto& oa = a.options.all();
  const auto& ob = b.options.all();
  for (const auto& [name, value] : oa) {
    const auto it = ob.find(name);
    if (it == ob.end()) {
      out.push_back(fmt::format("option {} {} -> (none)", name, text(value)));
    } else if (it->second != value) {
      out.push_back(fmt::format("option {} {} -> {}", name, text(value), text(it->second)));
    }
  }
  for (const auto& [name, value] : ob) {
    if (!oa.contains(name)) out.push_back(fmt::format("option {} (none) -> {}", name, text(value)));
  }
  return out;
}

std::vector<std::string> changes(const ListenerPolicyConfig& a, const ListenerPolicyConfig& b) {
  std::vector<std::string> out;
  note(out, "access", to_string(a.access), to_string(b.access));
  note(out, "word_order", to_string(a.word_order), to_string(b.word_order));
  const auto allow = [](const net::AllowList& l) {
    std::vector<std::string> s;
    for (const auto& r : l) s.push_back(r.to_string());
    return l.empty() ? std::string("[any]") : fmt::format("[{}]", fmt::join(s, ", "));
  };
  note(out, "allow", allow(a.allow), allow(b.allow));
  const auto slots = [](const std::optional<std::size_t>& n) {
    return n ? std::to_string(*n) : std::string("[server]'s");
  };
  note(out, "max_clients", slots(a.max_clients), slots(b.max_clients));
  note(out, "tls_handshakes_per_s", a.handshakes.per_second, b.handshakes.per_second);
  if (a.tls && b.tls) {
    if (a.tls->roles != b.tls->roles) out.emplace_back("TLS roles");
    if (a.tls->cert != b.tls->cert || a.tls->key != b.tls->key || a.tls->ca != b.tls->ca) {
      out.emplace_back("TLS files");
    }
  }
  return out;
}

ConfigDiff diff_config(const Config& running, const Config& next) {
  ConfigDiff d;
  for (const DeviceConfig& n : next.devices) {
    const DeviceConfig* r = by_name(running.devices, n.name);
    if (r == nullptr) {
      d.devices_added.push_back(n.name);
    } else if (auto what = changes(*r, n); what.empty()) {
      d.devices_kept.push_back(n.name);
    } else {
      d.devices_changed.push_back({n.name, std::move(what)});
    }
  }
  for (const DeviceConfig& r : running.devices) {
    if (by_name(next.devices, r.name) == nullptr) d.devices_removed.push_back(r.name);
  }
  for (const BusConfig& n : next.buses) {
    const BusConfig* r = by_name(running.buses, n.name);
    if (r == nullptr) {
      d.buses_added.push_back(n.name);
    } else if (auto what = changes(*r, n); what.empty()) {
      d.buses_kept.push_back(n.name);
    } else {
      d.buses_reopened.push_back({n.name, std::move(what)});
    }
  }
  for (const BusConfig& r : running.buses) {
    if (by_name(next.buses, r.name) == nullptr) d.buses_removed.push_back(r.name);
  }
  return d;
}

bool same_place(const ListenerConfig& a, const ListenerConfig& b) {
  if (a.framing != b.framing) return false;
  if (a.framing == ListenerFraming::mbap) {
    return a.host == b.host && a.port == b.port &&
           a.policy.tls.has_value() == b.policy.tls.has_value();
  }
  if (a.ascii_timeout != b.ascii_timeout || a.rx_latency != b.rx_latency) return false;
  if (a.serial || b.serial) {
    if (!a.serial || !b.serial) return false;
    BusConfig x = *a.serial;
    x.line = b.serial->line;  // where it is written in the file is no change
    return x == *b.serial;
  }
  return a.host == b.host && a.port == b.port;
}

namespace {

bool mbap(const ListenerConfig& l) {
  return l.framing == ListenerFraming::mbap;
}

// The Modbus TCP listeners a restart changes: each new one no running one is, then each running
// one no new one is.
std::vector<std::string> tcp_restart(const std::vector<ListenerConfig>& running,
                                     const std::vector<ListenerConfig>& next) {
  std::vector<std::string> out;
  const auto in = [](const std::vector<ListenerConfig>& list, const ListenerConfig& l) {
    return std::any_of(list.begin(), list.end(),
                       [&](const ListenerConfig& x) { return mbap(x) && same_place(x, l); });
  };
  for (const auto& n : next) {
    if (mbap(n) && !in(running, n)) out.push_back(listener_name(n));
  }
  for (const auto& r : running) {
    if (mbap(r) && !in(next, r)) out.push_back(listener_name(r) + " (removed)");
  }
  return out;
}

// The RTU / ASCII listeners a restart changes: each running one (those on serial lines first)
// no new one is, then each new one no running one is.
std::vector<std::string> serial_restart(const std::vector<ListenerConfig>& running,
                                        const std::vector<ListenerConfig>& next) {
  std::vector<std::string> out;
  std::vector<bool> matched(next.size(), false);
  for (const bool on_line : {true, false}) {
    for (const auto& r : running) {
      if (mbap(r) || r.serial.has_value() != on_line) continue;
      bool found = false;
      for (std::size_t i = 0; i < next.size() && !found; ++i) {
        if (!mbap(next[i]) && same_place(next[i], r)) found = matched[i] = true;
      }
      if (!found) out.push_back(listener_name(r) + " (removed or moved)");
    }
  }
  for (std::size_t i = 0; i < next.size(); ++i) {
    if (!mbap(next[i]) && !matched[i]) out.push_back(listener_name(next[i]) + " (added)");
  }
  return out;
}

std::vector<std::string> limit_changes(const ServerConfig& a, const ServerConfig& b) {
  std::vector<std::string> out;
  note(out, "max_clients", a.max_clients, b.max_clients);
  note(out, "idle_timeout_ms", a.idle_timeout.count(), b.idle_timeout.count());
  note(out, "frame_timeout_ms", a.frame_timeout.count(), b.frame_timeout.count());
  return out;
}

bool same_http(const HttpConfig& a, const HttpConfig& b) {
  return a.enabled == b.enabled && a.listen.host == b.listen.host &&
         a.listen.port == b.listen.port && a.allow == b.allow && a.capture == b.capture &&
         a.requests_per_s == b.requests_per_s;
}

bool same_history(const HistoryConfig& a, const HistoryConfig& b) {
  return a.events == b.events && a.commands == b.commands && a.refusals == b.refusals &&
         a.trend_seconds == b.trend_seconds;
}

}  // namespace

ReloadPlan plan_reload(const Config& running, const Config& next) {
  ReloadPlan p;
  p.tcp_listeners_restart = tcp_restart(running.listeners, next.listeners);
  p.serial_listeners_restart = serial_restart(running.listeners, next.listeners);
  for (const auto& n : next.listeners) {
    // Matched by name: a serial listener by its port (their addresses are all ":0").
    const auto r =
        std::find_if(running.listeners.begin(), running.listeners.end(),
                     [&](const ListenerConfig& l) { return listener_name(l) == listener_name(n); });
    if (r == running.listeners.end()) continue;
    if (auto what = changes(r->policy, n.policy); !what.empty()) {
      p.listener_policies.push_back({listener_name(n), std::move(what)});
    }
  }
  p.server_limits = limit_changes(running.server, next.server);
  if (!same_http(running.http, next.http)) p.sections_restart.emplace_back("[http]");
  if (!same_history(running.history, next.history)) p.sections_restart.emplace_back("[history]");
  MqttConfig mqtt = next.mqtt;
  mqtt.line = running.mqtt.line;  // where it is in the file is no change
  p.mqtt_session = !(mqtt == running.mqtt);
  return p;
}

void ReloadPlan::keep_what_waits(const Config& running, Config& next) const {
  if (!tcp_listeners_restart.empty() || !serial_listeners_restart.empty()) {
    next.listeners = running.listeners;
  }
  if (std::find(sections_restart.begin(), sections_restart.end(), "[http]") !=
      sections_restart.end()) {
    next.http = running.http;
  }
  next.history = running.history;  // equal, or waiting for a restart
}

}  // namespace drivegate
