// Where a write comes from, for the audit trail (history/command_audit.h, IEC 62443-3-3 SR 2.8):
// the kind of northbound, and whatever that northbound knows of the client. Every northbound
// fills it in the session it passes with each request (session.h); the gateway's own writes (the
// failsafe's, shutdown's) name themselves.
//
// Header-only, in dg_gateway_api with session.h.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace drivegate {

enum class SourceKind : std::uint8_t {
  modbus,      // a Modbus TCP client on a plain listener
  modbus_tls,  // a Modbus/TCP Security client (its certificate's subject and role)
  modbus_serial,   // a Modbus RTU / ASCII master on a serial listener's line
  modbus_rtu_tcp,  // a client sending Modbus RTU frames over TCP
  mqtt,        // a Sparkplug DCMD through the broker
  cli,         // `drivegate write` on the line, daemon stopped
  failsafe,    // the PLC-loss failsafe's own stop (docs/safety.md)
  shutdown,    // the daemon stopping its drives as it stops
  gateway,     // any other write of the gateway's own (on_start = stop)
};

// Their names in the journal (SOURCE=), the event history and the metrics' `source` label.
inline constexpr std::array<std::string_view, 9> kSourceKindNames = {
    "modbus", "modbus_tls", "modbus_serial", "modbus_rtu_tcp", "mqtt", "cli",
    "failsafe",   "shutdown",   "gateway"};
constexpr std::string_view to_string(SourceKind k) {
  return kSourceKindNames.at(static_cast<std::size_t>(k));
}

struct Source {
  SourceKind kind = SourceKind::gateway;
  // Modbus: the listener's name ("0.0.0.0:502"); MQTT: the broker ("mqtt.plant:8883").
  std::string listener;
  // Modbus: the client's address and port ("192.0.2.7:50122"); MQTT: the Sparkplug primary host
  // the commands are expected from, if one is configured (a DCMD does not say who published it).
  std::string client;
  std::string subject;  // a TLS client certificate's subject ("CN=plc-1,O=plant")
  std::string role;     // the role its certificate carried, if any
};

}  // namespace drivegate
