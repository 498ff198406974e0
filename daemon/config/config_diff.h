// What a reload changes (Daemon::reload, Gateway::adopt), and the one statement of what a reload
// does with each part of the configuration (plan_reload):
//   devices and buses   by name: a device whose settings are all the same is kept as it runs
//                       (its driver, command in force, failsafe timer and latch, counters),
//                       whatever else changes on its line; a bus whose own settings are the same
//                       keeps its port open, whatever its devices do; the rest start afresh
//   [server] limits     applied at once (modbus::Server::set_limits says how)
//   listener policies   applied at once, open connections included (access, word order, allow,
//                       roles, TLS files, max_clients, handshakes, write_reply, broadcast...)
//   listener places     a listener added, removed, or whose address, port, TLS-ness, framing or
//                       line changed: at the next restart (sockets and ports are opened once)
//   [http], [history]   at the next restart
//   [mqtt]              anything but its line changed: the session ends and a new one begins
// Pure: two configurations in, the differences out, each said in words for the log.
#pragma once

#include <string>
#include <vector>

#include "config/config.h"

namespace drivegate {

// Equal but for where in the file they were declared.
bool same_settings(const BusConfig& a, const BusConfig& b);
bool same_settings(const DeviceConfig& a, const DeviceConfig& b);

// What differs, one "key old -> new" each ("baud 9600 -> 19200", "poll_ms 500 -> 250",
// "option monitors [0D00] -> [0D00, 0D01]"); empty when the settings are the same.
std::vector<std::string> changes(const BusConfig& running, const BusConfig& next);
std::vector<std::string> changes(const DeviceConfig& running, const DeviceConfig& next);
// A listener's policy, which a reload applies to it as it runs ("access operate -> read",
// "allow [192.168.1.0/24] -> [any]", "word_order big -> little", "TLS roles", "TLS files").
std::vector<std::string> changes(const ListenerPolicyConfig& running,
                                 const ListenerPolicyConfig& next);

struct Changed {
  std::string name;
  std::vector<std::string> what;  // changes()
};

struct ConfigDiff {
  std::vector<std::string> devices_kept, devices_added, devices_removed;
  std::vector<Changed> devices_changed;  // started afresh
  std::vector<std::string> buses_kept, buses_added, buses_removed;
  std::vector<Changed> buses_reopened;
};

ConfigDiff diff_config(const Config& running, const Config& next);

// Whether `next` is the listener `running` is, in a place a reload can leave open: the same
// framing and socket (a Modbus TCP one: address, port, TLS or not; RTU / ASCII: the serial line,
// or the address and port, and their timing). Else only a restart applies it.
bool same_place(const ListenerConfig& running, const ListenerConfig& next);

struct ReloadPlan {
  // Listeners a restart would add, remove or move, by name, as the log and the history say them:
  // Modbus TCP ones ("127.0.0.1:1502", "0.0.0.0:502 (removed)"), then RTU / ASCII ones
  // ("serial /dev/ttyS1 (rtu) (removed or moved)", "... (added)"). Their running ones go on.
  std::vector<std::string> tcp_listeners_restart;
  std::vector<std::string> serial_listeners_restart;
  // Applied to running listeners at once: each listener's changed policy, by name.
  std::vector<Changed> listener_policies;
  // [server]: applied at once, "max_clients 32 -> 64", "idle_timeout_ms ...".
  std::vector<std::string> server_limits;
  // Sections kept as they run until the next restart: "[http]", "[history]".
  std::vector<std::string> sections_restart;
  bool mqtt_session = false;  // [mqtt] changed: a new Sparkplug session

  // `next` with what waits for a restart as it runs in `running`: the listeners (when any waits),
  // [http] and [history].
  void keep_what_waits(const Config& running, Config& next) const;
};

ReloadPlan plan_reload(const Config& running, const Config& next);

}  // namespace drivegate
