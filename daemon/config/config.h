// The gateway's configuration, as loaded from one TOML file and validated. Every value here has
// been checked against its range and, for device options, against the adapter's schema.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "drivegate/adapter.h"
#include "gateway/session.h"
#include "net/address_rate.h"
#include "net/allow_list.h"
#include "net/listen_host.h"

namespace drivegate {

// [server]: what all listeners share.
struct ServerConfig {
  std::size_t max_clients = 32;  // every listener's clients together
  Millis idle_timeout{60'000};
  Millis frame_timeout{2'000};
};

struct ListenAddress {
  std::string host;
  std::uint16_t port = 0;
};

// A listener's Modbus/TCP Security (tls = { cert, key, ca } and roles): the files its TLS
// context is made of, and the access level each role a client certificate carries gets.
// Role names, as client certificates carry them, to the access level each gets.
using TlsRoles = std::map<std::string, AccessLevel, std::less<>>;

struct ListenerTlsConfig {
  std::filesystem::path cert;  // PEM: the server's certificate (chain)
  std::filesystem::path key;   // PEM: its private key
  std::filesystem::path ca;    // PEM: the CA(s) a client certificate must be signed by
  TlsRoles roles;              // a role not in here, or no role, gets the listener's access
  friend bool operator==(const ListenerTlsConfig&, const ListenerTlsConfig&) = default;
};

// Who a listener serves and what they may do: what a reload applies to a running listener.
struct ListenerPolicyConfig {
  net::AllowList allow;  // client addresses served; empty: every address
  // Plain TCP: every client's level. TLS: the level of a client whose certificate carries no
  // role in tls->roles.
  AccessLevel access = AccessLevel::maintain;
  WordOrder word_order = WordOrder::big;
  std::optional<ListenerTlsConfig> tls;
  std::optional<std::size_t> max_clients;  // its own connection slots; none: [server]'s
  // TLS handshakes one client address may start (tls_handshakes_per_s).
  net::RateLimit handshakes = net::RateLimit::per_second_in_bursts_of_two(5);
  friend bool operator==(const ListenerPolicyConfig&, const ListenerPolicyConfig&) = default;
};

// [http]: the status page, its JSON and /metrics. Off unless the file has [http].
struct HttpConfig {
  bool enabled = false;
  ListenAddress listen{"127.0.0.1", 8502};
  net::AllowList allow;          // empty: every address
  bool capture = false;          // whether /api/v1/capture is served
  unsigned requests_per_s = 20;  // per client address, bursts of twice that; 0: no limit
  int line = 0;
};

// [history]: what the daemon keeps of what happened (docs/audit.md). The audit trail goes to
// the journal whatever this says; these bound what is kept in memory besides.
struct HistoryConfig {
  // Entries the event history keeps on each shelf (history/event_log.h); 0: none kept there.
  std::size_t events = 2000;        // the plant's events and the gateway's own writes
  std::size_t commands = 2000;      // clients' writes carried out
  std::size_t refusals = 2000;      // clients' writes refused
  std::size_t trend_seconds = 600;  // seconds of trends at one sample a second; 0: none
  int line = 0;
  bool operator==(const HistoryConfig&) const = default;
};

// [mqtt]: the Sparkplug B northbound (docs/mqtt.md). Off unless the file has [mqtt].
// One broker of [mqtt]: `broker`, or each of `brokers`.
struct MqttBroker {
  std::string url;  // as written, for messages: mqtt://host[:port] or mqtts://host[:port]
  std::string host;
  std::uint16_t port = 1883;
  bool tls = false;
  std::filesystem::path ca;  // mqtts: the CA the broker's certificate chains to
  std::filesystem::path cert;
  std::filesystem::path key;  // mqtts: a client certificate, both or neither
  friend bool operator==(const MqttBroker&, const MqttBroker&) = default;
};

inline constexpr std::size_t kMaxBrokers = 8;

// The form of the primary host's STATE message (primary_host_state): Sparkplug 3.0's, or 2.2's.
enum class MqttHostState : std::uint8_t { v3_0, v2_2 };

struct MqttConfig {
  bool enabled = false;
  // In the order they are tried: the edge node walks to the next when one fails (docs/mqtt.md).
  std::vector<MqttBroker> brokers;
  std::string client_id;  // default "drivegate-" + edge_node_id
  std::string group_id;
  std::string edge_node_id;
  std::string primary_host_id;  // empty: publish without waiting for a primary host
  MqttHostState primary_host_state = MqttHostState::v3_0;  // its STATE's form
  std::string username;
  std::filesystem::path password_file;                   // its first line is the password
  std::string password;                                  // read from password_file at load
  std::vector<std::pair<std::string, double>> deadband;  // point name -> how far it must move
  Millis min_interval{100};                              // per device, between two DDATA
  Millis counter_interval{10'000};  // counters change with every frame: reported this often
  std::chrono::seconds keepalive{30};
  bool commands = false;                      // DCMD writes
  AccessLevel access = AccessLevel::operate;  // what a DCMD may write
  bool feed_failsafe = false;                 // whether a DCMD proves the PLC is there
  // Store and forward (docs/mqtt.md): changes kept on disk while there is no session, in the
  // state directory (drivegated --state-dir; without one, nothing is kept).
  bool store_forward = true;
  std::uint64_t store_max_bytes = 64ULL * 1024 * 1024;
  std::chrono::seconds store_max_age{24 * 3600};
  unsigned replay_per_s = 500;  // historical DDATA a second once a session is back
  int line = 0;
  friend bool operator==(const MqttConfig&, const MqttConfig&) = default;
};

struct BusConfig {
  std::string name;
  std::string port;  // device path, tcp://host:port or rfc2217://host:port (port_address.h)
  std::uint32_t baud = 0;
  Parity parity = Parity::none;
  std::uint8_t data_bits = 8;
  std::uint8_t stop_bits = 1;
  bool echo = false;   // one-wire: discard (and check) our own bytes
  bool rs485 = false;  // kernel RS-485 mode (TIOCSRS485)
  Millis reopen_max{10'000};
  Millis network_delay{0};  // added to every reply timeout (a serial device server's latency)
  int line = 0;             // where it was declared, for messages
  friend bool operator==(const BusConfig&, const BusConfig&) = default;
};

// What a listener's frames are (docs/serial-listeners.md): Modbus TCP's MBAP, or the serial
// line's RTU or ASCII, on a serial port or on TCP.
enum class ListenerFraming : std::uint8_t { mbap, rtu, ascii };
inline constexpr std::array<std::string_view, 3> kListenerFramingNames = {"mbap", "rtu", "ascii"};
constexpr std::string_view to_string(ListenerFraming f) {
  return kListenerFramingNames.at(static_cast<std::size_t>(f));
}
// When a serial master's write is answered (write_reply).
enum class WriteReply : std::uint8_t {
  confirmed,  // when the drive took it (or the exception when it did not), as on TCP
  accepted,   // as soon as it is validated and queued; the register image then shows the truth
};
inline constexpr std::array<std::string_view, 2> kWriteReplyNames = {"confirmed", "accepted"};
constexpr std::string_view to_string(WriteReply w) {
  return kWriteReplyNames.at(static_cast<std::size_t>(w));
}

// The shortest reply_timeout_ms a serial listener takes (0 aside): below it no confirmed write
// could ever be answered.
inline constexpr Millis kMinReplyTimeout{20};

// One [[listener]], or the one listener [server] listen declares.
struct ListenerConfig {
  // A TCP listener's address: a numeric IPv4 or IPv6 address ("[::1]" accepted), "localhost",
  // or "" / "*" for every interface (net/listen_host.h); port 0: an ephemeral one. A serial
  // listener's are "" and 0.
  std::string host = "*";
  std::uint16_t port = 502;
  ListenerPolicyConfig policy;
  ListenerFraming framing = ListenerFraming::mbap;
  // A serial listener (`port` instead of `address`): the master's line, with a bus's settings.
  std::optional<BusConfig> serial;
  // RTU / ASCII listeners only.
  WriteReply write_reply = WriteReply::confirmed;
  bool broadcast = false;  // apply writes sent to address 0
  // The master's response timeout: a reply that could leave only later is dropped, never sent
  // (0: none; a reply waits for the drive however long it takes; else at least kMinReplyTimeout).
  Millis reply_timeout{0};
  Millis ascii_timeout{1000};  // Serial Line 2.5.2.1: between two characters of a frame
  // A serial listener's port may hand over received bytes this late (a UART's FIFO, a USB
  // adapter's latency timer): pauses inside an RTU frame up to this are the port's.
  Millis rx_latency{20};
  // Declared by [server] listen (or by nothing: the default 0.0.0.0:502): plain TCP, every
  // address, access maintain, as before listeners existed.
  bool from_server_listen = false;
  int line = 0;
};

// How the log, the register map, the reload log and the status documents name a listener, one
// name per listener: a Modbus TCP one by its address ("0.0.0.0:502", "[::]:802 (TLS)"), one of RTU
// or ASCII frames on TCP by its address and framing ("0.0.0.0:5020 (rtu over tcp)"), a serial
// one by its port and framing ("serial /dev/ttyS1 (rtu)"), as the listeners name themselves in
// the log (modbus/serial_listener.cpp, modbus/rtu_tcp_listener.cpp).
inline std::string listener_name(const ListenerConfig& l) {
  if (l.serial) return "serial " + l.serial->port + " (" + std::string(to_string(l.framing)) + ")";
  if (l.framing != ListenerFraming::mbap) {
    return net::listen_name(l.host, l.port, false) + " (" + std::string(to_string(l.framing)) +
           " over tcp)";
  }
  return net::listen_name(l.host, l.port, l.policy.tls.has_value());
}

// What the gateway does to a drive whose PLC stopped writing (docs/safety.md).
enum class FailsafeAction : std::uint8_t {
  stop,        // Command::stop
  quick_stop,  // Command::quick_stop (a plain stop where the drive refuses it)
  hold,        // leave the drive as it is; only the status bit says so
  preset,      // a running drive goes to `failsafe_rpm` (a stopped one stays stopped)
};
// Their names in drivegate.toml (`failsafe_action`) and in the log, in enum order.
inline constexpr std::array<std::string_view, 4> kFailsafeActionNames = {"stop", "quick_stop",
                                                                         "hold", "preset"};
constexpr std::string_view to_string(FailsafeAction a) {
  return kFailsafeActionNames.at(static_cast<std::size_t>(a));
}
// What the gateway does to a running drive when the daemon shuts down.
enum class ShutdownAction : std::uint8_t { stop, hold };
// What the gateway does with a drive it finds running when it first reaches it (daemon start, a
// device added or changed by a reload): adopt shows the run the drive reports and leaves it be;
// stop stops it and logs so (docs/safety.md, "Starting").
enum class StartAction : std::uint8_t { adopt, stop };

struct FailsafeConfig {
  Millis timeout{0};  // no valid write to command / setpoint / heartbeat for this long; 0 = off
  FailsafeAction action = FailsafeAction::stop;
  std::int32_t preset_rpm = 0;  // for FailsafeAction::preset
  friend bool operator==(const FailsafeConfig&, const FailsafeConfig&) = default;
};

struct DeviceConfig {
  std::string name;
  std::string bus;
  std::string adapter;
  std::uint8_t unit_id = 0;
  std::uint32_t address = 0;
  Millis poll_interval{500};
  Millis budget{1'000};       // most line time one turn of this device may take
  Millis backoff_max{5'000};  // longest pause between probes of a silent device
  FailsafeConfig failsafe;
  ShutdownAction on_shutdown = ShutdownAction::stop;
  StartAction on_start = StartAction::adopt;
  Options options;
  // What its adapter read beyond these settings to make the device (Driver::files_read: a
  // profile's file and a fingerprint of its content). Empty from the loader; the gateway fills it
  // in when it builds the device, so that a reload compares it like a setting.
  std::string files_read;
  int line = 0;
  friend bool operator==(const DeviceConfig&, const DeviceConfig&) = default;
};

struct Config {
  std::filesystem::path path;
  std::filesystem::path plugin_dir;  // empty: the built-in default
  ServerConfig server;
  std::vector<ListenerConfig> listeners;  // at least one
  HttpConfig http;
  HistoryConfig history;
  MqttConfig mqtt;
  std::vector<BusConfig> buses;
  std::vector<DeviceConfig> devices;
};

}  // namespace drivegate
