#include "mqtt/sparkplug.h"

#include <array>
#include <cctype>
#include <charconv>

namespace drivegate::sparkplug {

namespace {

// Spec 4.1.1: the message_type element, in MessageType order.
constexpr std::array<std::string_view, 8> kTypeNames = {"NBIRTH", "NDEATH", "DBIRTH", "DDEATH",
                                                        "NDATA",  "DDATA",  "NCMD",   "DCMD"};

bool is_device_message(MessageType t) {
  return t == MessageType::dbirth || t == MessageType::ddeath || t == MessageType::ddata ||
         t == MessageType::dcmd;
}

// A minimal reader for the STATE payload: one flat JSON object whose values are literals.
class JsonObjectReader {
 public:
  explicit JsonObjectReader(std::string_view s) : s_(s) {}

  // Calls on_member(key, raw value) for each member; false on any syntax it does not accept.
  template <class F>
  bool members(F on_member) {
    skip();
    if (!eat('{')) return false;
    skip();
    if (eat('}')) return done();
    while (true) {
      std::string key;
      if (!string(key)) return false;
      skip();
      if (!eat(':')) return false;
      skip();
      const std::size_t start = i_;
      if (peek() == '"') {
        std::string ignored;
        if (!string(ignored)) return false;
      } else {
        while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) != 0 ||
                                  s_[i_] == '-' || s_[i_] == '+' || s_[i_] == '.')) {
          ++i_;
        }
        if (i_ == start) return false;
      }
      on_member(key, s_.substr(start, i_ - start));
      skip();
      if (eat('}')) return done();
      if (!eat(',')) return false;
      skip();
    }
  }

 private:
  bool done() {
    skip();
    return i_ == s_.size();
  }
  char peek() const { return i_ < s_.size() ? s_[i_] : '\0'; }
  bool eat(char c) {
    if (peek() != c) return false;
    ++i_;
    return true;
  }
  void skip() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_])) != 0) ++i_;
  }
  // A string without escapes other than \" and \\ (keys here are plain words).
  bool string(std::string& out) {
    if (!eat('"')) return false;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\') {
        if (++i_ >= s_.size()) return false;
      }
      out += s_[i_++];
    }
    return eat('"');
  }
  std::string_view s_;
  std::size_t i_ = 0;
};

}  // namespace

bool value_fits(DataType type, const MetricValue& value) {
  if (std::holds_alternative<std::monostate>(value)) return true;
  switch (type) {
    case DataType::int8:
    case DataType::int16:
    case DataType::int32:
    case DataType::int64:
      return std::holds_alternative<std::int64_t>(value);
    case DataType::uint8:
    case DataType::uint16:
    case DataType::uint32:
    case DataType::uint64:
      return std::holds_alternative<std::uint64_t>(value);
    case DataType::float32:
    case DataType::float64:
      return std::holds_alternative<double>(value);
    case DataType::boolean:
      return std::holds_alternative<bool>(value);
    case DataType::string:
    case DataType::text:
      return std::holds_alternative<std::string>(value);
    case DataType::unknown:
      break;
  }
  return false;
}

std::optional<double> number_of(const MetricValue& value) {
  if (const auto* i = std::get_if<std::int64_t>(&value)) return static_cast<double>(*i);
  if (const auto* u = std::get_if<std::uint64_t>(&value)) return static_cast<double>(*u);
  if (const auto* d = std::get_if<double>(&value)) return *d;
  if (const auto* b = std::get_if<bool>(&value)) return *b ? 1.0 : 0.0;
  return std::nullopt;
}

std::string_view to_string(MessageType t) {
  return kTypeNames.at(static_cast<std::size_t>(t));
}

std::string topic(std::string_view group, MessageType type, std::string_view edge_node,
                  std::string_view device) {
  std::string t;
  t.reserve(kNamespace.size() + group.size() + edge_node.size() + device.size() + 12);
  t.append(kNamespace).append("/").append(group).append("/").append(to_string(type));
  t.append("/").append(edge_node);
  if (!device.empty()) t.append("/").append(device);
  return t;
}

std::optional<Topic> parse_topic(std::string_view topic) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t slash = topic.find('/', start);
    parts.push_back(topic.substr(start, slash - start));
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  if (parts.size() < 4 || parts.size() > 5 || parts[0] != kNamespace) return std::nullopt;
  std::optional<MessageType> type;
  for (std::size_t i = 0; i < kTypeNames.size(); ++i) {
    if (parts[2] == kTypeNames[i]) type = static_cast<MessageType>(i);
  }
  if (!type || is_device_message(*type) != (parts.size() == 5)) return std::nullopt;
  for (std::size_t i = 1; i < parts.size(); ++i) {
    if (i != 2 && !valid_id(parts[i])) return std::nullopt;
  }
  return Topic{*type, std::string(parts[1]), std::string(parts[3]),
               parts.size() == 5 ? std::string(parts[4]) : std::string()};
}

bool valid_id(std::string_view id) {
  return !id.empty() && id.find_first_of("/+#") == std::string_view::npos;
}

std::string state_topic(std::string_view host_id, HostStateForm form) {
  if (form == HostStateForm::v2_2) return "STATE/" + std::string(host_id);
  return std::string(kNamespace) + "/STATE/" + std::string(host_id);
}

std::optional<HostState> parse_host_state(std::string_view payload, HostStateForm form) {
  if (form == HostStateForm::v2_2) {
    if (payload == "ONLINE") return HostState{true, 0};
    if (payload == "OFFLINE") return HostState{false, 0};
    return std::nullopt;
  }
  const std::string_view json = payload;
  std::optional<bool> online;
  std::optional<std::uint64_t> timestamp;
  bool bad = false;
  JsonObjectReader reader(json);
  const bool ok = reader.members([&](const std::string& key, std::string_view raw) {
    if (key == "online") {
      if (raw == "true") {
        online = true;
      } else if (raw == "false") {
        online = false;
      } else {
        bad = true;
      }
    } else if (key == "timestamp") {
      std::uint64_t v = 0;
      const auto [end, ec] = std::from_chars(raw.data(), raw.data() + raw.size(), v);
      if (ec != std::errc() || end != raw.data() + raw.size()) {
        bad = true;
      } else {
        timestamp = v;
      }
    }
  });
  if (!ok || bad || !online || !timestamp) return std::nullopt;
  return HostState{*online, *timestamp};
}

}  // namespace drivegate::sparkplug
