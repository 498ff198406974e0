// Sparkplug B 3.0 as drivegate speaks it, in plain C++ types: data types, metrics, payloads and
// topics (Eclipse Sparkplug Specification 3.0.0). Nothing here does I/O or knows a clock;
// sparkplug_codec.cpp turns a Payload into the protobuf bytes on the wire and back.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace drivegate::sparkplug {

// Spec 6.4.16 "Datatype Details": the numbers a metric's datatype field carries. Only the ones
// drivegate publishes or accepts in a command are named here.
enum class DataType : std::uint32_t {
  unknown = 0,
  int8 = 1,
  int16 = 2,
  int32 = 3,
  int64 = 4,
  uint8 = 5,
  uint16 = 6,
  uint32 = 7,
  uint64 = 8,
  float32 = 9,   // "Float"
  float64 = 10,  // "Double"
  boolean = 11,
  string = 12,
  text = 14,
};

// A metric's or property's value: null (std::monostate), a signed or unsigned integer, a floating
// point number, a boolean or a string. Which one goes with which DataType: value_fits().
using MetricValue =
    std::variant<std::monostate, std::int64_t, std::uint64_t, double, bool, std::string>;

// Whether `value` is a value of `type` (a null fits every type).
bool value_fits(DataType type, const MetricValue& value);

// The value as a double when it is a number or a boolean (true = 1).
std::optional<double> number_of(const MetricValue& value);

struct Property {
  std::string key;  // "engUnit", "engLow", "engHigh", "readOnly", "Documentation"
  DataType type = DataType::string;
  MetricValue value;
  bool operator==(const Property&) const = default;
};

struct Metric {
  std::string name;
  DataType type = DataType::unknown;
  MetricValue value;  // std::monostate: is_null
  std::vector<Property> properties;
  // When the value was true at its source (ms since the Unix epoch, spec 6.4.4); none: the
  // payload's timestamp.
  std::optional<std::uint64_t> timestamp;
  // Spec 6.4.x is_historical: a value from the past (store and forward), not the current one.
  bool historical = false;
};

struct Payload {
  std::uint64_t timestamp = 0;       // ms since the Unix epoch (spec 6.4.1)
  std::optional<std::uint64_t> seq;  // absent in NDEATH (spec 6.4.1)
  std::vector<Metric> metrics;
};

// --- Topics (spec 4.1): spBv1.0/<group_id>/<message_type>/<edge_node_id>[/<device_id>] ---

inline constexpr std::string_view kNamespace = "spBv1.0";

enum class MessageType : std::uint8_t { nbirth, ndeath, dbirth, ddeath, ndata, ddata, ncmd, dcmd };

std::string_view to_string(MessageType t);  // "NBIRTH" ...

// The topic of a node message (device empty) or a device message.
std::string topic(std::string_view group, MessageType type, std::string_view edge_node,
                  std::string_view device = {});

struct Topic {
  MessageType type;
  std::string group;
  std::string edge_node;
  std::string device;  // empty for node messages
};

// A Sparkplug topic's parts, or nullopt when `topic` is not one (STATE included: see below).
std::optional<Topic> parse_topic(std::string_view topic);

// Whether `id` may be a group, edge node or device id: not empty, no '/', '+' or '#' (spec 4.1).
bool valid_id(std::string_view id);

// --- The primary host application's state ---
// 3.0 (spec 4.2.1): spBv1.0/STATE/<host_id>, retained, UTF-8 JSON {"online": true|false,
//   "timestamp": <ms>}; a STATE older than the newest seen is stale.
// 2.2 (Sparkplug B 2.2, "Primary Application State", which deployed hosts still publish):
//   STATE/<host_id>, outside the namespace, retained, the UTF-8 text ONLINE or OFFLINE; no
//   timestamp, so the broker's order is the only order.

enum class HostStateForm : std::uint8_t { v3_0, v2_2 };

std::string state_topic(std::string_view host_id, HostStateForm form = HostStateForm::v3_0);

struct HostState {
  bool online = false;
  std::uint64_t timestamp = 0;  // 2.2: always 0
};

// nullopt when `payload` is not the form's: 3.0 an object with a boolean "online" and an integer
// "timestamp"; 2.2 exactly ONLINE or OFFLINE.
std::optional<HostState> parse_host_state(std::string_view payload,
                                          HostStateForm form = HostStateForm::v3_0);

}  // namespace drivegate::sparkplug
